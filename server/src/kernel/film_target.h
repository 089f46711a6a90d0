// The kernel's RenderTarget: a job's film behind its lock, progress and
// the cancellation flag.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <optional>

#include "kernel/film.h"
#include "yarf/transport.h"

namespace yarf {

class FilmTarget final : public RenderTarget {
 public:
  using PassCallback = std::function<void(uint32_t samples_done)>;

  // Which samples of which pixels to render.
  struct Share {
    uint32_t first_sample = 0;
    std::optional<PixelWindow> crop;
  };

  // `mutex` guards `film` for everyone who reads it while it renders.
  FilmTarget(Film& film, std::mutex& mutex, uint32_t spp, uint64_t seed, Share share,
             const std::atomic<bool>& cancel, PassCallback on_pass)
      : film_(film), mutex_(mutex), spp_(spp), seed_(seed), share_(share), cancel_(cancel),
        on_pass_(std::move(on_pass)), samples_done_(share.first_sample) {}

  // What each camera sample's radiance counts for (π for an irradiance
  // meter: KernelScene::CameraRayWeight); 1 unless set.
  void WeighCameraSamples(float weight) { camera_weight_ = weight; }

  uint32_t SamplesPerPixel() const override { return spp_; }
  uint32_t FirstSample() const override { return share_.first_sample; }
  std::optional<PixelWindow> Crop() const override { return share_.crop; }
  uint64_t Seed() const override { return seed_; }
  bool Cancelled() const override { return cancel_.load(std::memory_order_relaxed); }
  void Accumulate(const FilmSamples& samples) override;
  void PassDone(uint32_t samples_done) override;

 private:
  Film& film_;
  std::mutex& mutex_;
  uint32_t spp_;
  uint64_t seed_;
  Share share_;
  const std::atomic<bool>& cancel_;
  PassCallback on_pass_;
  uint32_t samples_done_;
  float camera_weight_ = 1;
};

}  // namespace yarf
