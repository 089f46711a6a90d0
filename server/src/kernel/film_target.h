// The kernel's RenderTarget: a job's film behind its lock, progress and
// the cancellation flag.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>

#include "kernel/film.h"
#include "yarf/transport.h"

namespace yarf {

class FilmTarget final : public RenderTarget {
 public:
  using PassCallback = std::function<void(uint32_t samples_done)>;

  // `mutex` guards `film` for everyone who reads it while it renders.
  FilmTarget(Film& film, std::mutex& mutex, uint32_t spp, uint64_t seed,
             const std::atomic<bool>& cancel, PassCallback on_pass)
      : film_(film), mutex_(mutex), spp_(spp), seed_(seed), cancel_(cancel),
        on_pass_(std::move(on_pass)) {}

  uint32_t SamplesPerPixel() const override { return spp_; }
  uint64_t Seed() const override { return seed_; }
  bool Cancelled() const override { return cancel_.load(std::memory_order_relaxed); }
  void Accumulate(const FilmSamples& samples) override;
  void PassDone(uint32_t samples_done) override;

 private:
  Film& film_;
  std::mutex& mutex_;
  uint32_t spp_;
  uint64_t seed_;
  const std::atomic<bool>& cancel_;
  PassCallback on_pass_;
  uint32_t samples_done_ = 0;
};

}  // namespace yarf
