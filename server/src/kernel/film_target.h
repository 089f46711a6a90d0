// The kernel's RenderTarget: a job's film, progress and the cancellation
// flag.
//
// Render threads add to the film without waiting for each other: the film
// is cut into blocks of kBlockSide × kBlockSide pixels with a mutex each,
// and a batch holds the lock of the block its samples go to, one block at
// a time (a sample near a block's edge goes to each block it reaches, its
// pixels there alone). Whoever reads the whole film meanwhile (progress
// images, checkpoints, results) and the end of a pass hold the film's
// FilmLock alone; batches hold it shared.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>

#include "kernel/film.h"
#include "yarf/transport.h"

namespace yarf {

// A film's lock: shared by the threads that add samples, held alone by the
// readers of the whole film. std::shared_mutex (glibc's) lets new shared
// holders in while an exclusive one waits, so with many render threads a
// reader might wait as long as the render; here a waiting reader keeps new
// writers out until it has had its turn.
class FilmLock {
 public:
  void lock();
  void unlock() { mutex_.unlock(); }
  void lock_shared();
  void unlock_shared() { mutex_.unlock_shared(); }

 private:
  std::shared_mutex mutex_;
  // Only a hint of whom to let in first: the mutex is what excludes.
  std::atomic<uint32_t> readers_waiting_{0};
};

class FilmTarget final : public RenderTarget {
 public:
  using PassCallback = std::function<void(uint32_t samples_done)>;

  // Which samples of which pixels to render.
  struct Share {
    uint32_t first_sample = 0;
    std::optional<PixelWindow> crop;
  };

  // Side in pixels of the blocks written under one lock: as large as the
  // integrators' tiles, so that a tile's batch takes one block's lock or,
  // with a wide filter, those of a few blocks along its edges.
  static constexpr uint32_t kBlockSide = 32;

  // `lock` guards `film` for everyone who reads it while it renders.
  FilmTarget(Film& film, FilmLock& lock, uint32_t spp, uint64_t seed, Share share, const std::atomic<bool>& cancel,
             PassCallback on_pass);

  // What each camera sample's radiance counts for (π for an irradiance
  // meter: KernelScene::CameraRayWeight); 1 unless set.
  void WeighCameraSamples(float weight) { camera_weight_ = weight; }
  // How the film records a sample (v1::Film's exposure and
  // max_component_value, 0 for none): times `exposure`, then scaled down
  // to `max_component` if a component is above it. Whole-pixel estimates
  // are exposed alone.
  void Expose(float exposure, float max_component) {
    exposure_ = exposure;
    max_component_ = max_component > 0 ? max_component : kInfinity;
  }

  uint32_t SamplesPerPixel() const override { return spp_; }
  uint32_t FirstSample() const override { return share_.first_sample; }
  std::optional<PixelWindow> Crop() const override { return share_.crop; }
  uint64_t Seed() const override { return seed_; }
  bool Cancelled() const override { return cancel_.load(std::memory_order_relaxed); }
  void Accumulate(const FilmSamples& samples) override;
  void PassDone(uint32_t samples_done) override;
  float FilterRadius() const override { return film_.FilterRadius(); }
  float PixelWeight(uint32_t px, uint32_t py, float x, float y) const override;
  // Camera-sample weighted (WeighCameraSamples), as camera samples are.
  void AddPixelEstimates(const PixelWindow& window, uint32_t samples, std::span<const Vec3> values,
                         std::span<const Vec3> variances) override;

 private:
  // One cache line each: threads locking neighbouring blocks do not
  // contend for the line.
  struct alignas(64) BlockMutex {
    std::mutex mutex;
  };

  Film& film_;
  FilmLock& lock_;
  uint32_t spp_;
  uint64_t seed_;
  Share share_;
  const std::atomic<bool>& cancel_;
  PassCallback on_pass_;
  uint32_t samples_done_;
  // The sample's radiance as the film records it.
  Vec3 Recorded(Vec3 rgb, float weight) const;

  float camera_weight_ = 1;
  float exposure_ = 1, max_component_ = kInfinity;
  uint32_t block_columns_;
  std::unique_ptr<BlockMutex[]> block_mutexes_;
  std::once_flag splats_prepared_;
  mutable std::once_flag masses_prepared_;
};

}  // namespace yarf
