#include "kernel/film_target.h"

#include <algorithm>
#include <utility>

namespace yarf {

void FilmLock::lock() {
  readers_waiting_.fetch_add(1, std::memory_order_relaxed);
  mutex_.lock();
  if (readers_waiting_.fetch_sub(1, std::memory_order_relaxed) == 1) readers_waiting_.notify_all();
}

void FilmLock::lock_shared() {
  for (uint32_t waiting; (waiting = readers_waiting_.load(std::memory_order_relaxed)) != 0;)
    readers_waiting_.wait(waiting, std::memory_order_relaxed);
  mutex_.lock_shared();
}

FilmTarget::FilmTarget(Film& film, FilmLock& lock, uint32_t spp, uint64_t seed, Share share,
                       const std::atomic<bool>& cancel, PassCallback on_pass)
    : film_(film), lock_(lock), spp_(spp), seed_(seed), share_(share), cancel_(cancel),
      on_pass_(std::move(on_pass)), samples_done_(share.first_sample),
      block_columns_((film.width() + kBlockSide - 1) / kBlockSide),
      block_mutexes_(std::make_unique<BlockMutex[]>(size_t(block_columns_) *
                                                    ((film.height() + kBlockSide - 1) / kBlockSide))) {}

void FilmTarget::Accumulate(const FilmSamples& samples) {
  if (samples.Count() == 0) return;
  std::shared_lock adding(lock_);
  if (samples.splats) std::call_once(splats_prepared_, [&] { film_.PrepareSplats(); });
  // In batch order, so that each pixel sums its samples in the order it
  // would one by one. A block's lock is kept from one sample to the next
  // while they stay in it: a tile's samples come in runs in one block.
  std::unique_lock<std::mutex> held;
  const auto hold = [&](uint32_t bx, uint32_t by) {
    std::mutex& block = block_mutexes_[size_t(by) * block_columns_ + bx].mutex;
    if (held.mutex() == &block) return;
    if (held.owns_lock()) held.unlock();
    held = std::unique_lock(block);
  };
  for (size_t i = 0; i < samples.Count(); ++i) {
    const float x = samples.xy[2 * i], y = samples.xy[2 * i + 1];
    const PixelWindow footprint = film_.Footprint(x, y);
    if (footprint.x0 == footprint.x1) continue;
    const Vec3 value = Recorded(samples.rgb[i], samples.splats ? 1.0f : camera_weight_);
    // Each block the filter reaches, with the sample's pixels there.
    for (uint32_t by = footprint.y0 / kBlockSide; by <= (footprint.y1 - 1) / kBlockSide; ++by)
      for (uint32_t bx = footprint.x0 / kBlockSide; bx <= (footprint.x1 - 1) / kBlockSide; ++bx) {
        const PixelWindow pixels{std::max(footprint.x0, bx * kBlockSide), std::max(footprint.y0, by * kBlockSide),
                                 std::min(footprint.x1, (bx + 1) * kBlockSide),
                                 std::min(footprint.y1, (by + 1) * kBlockSide)};
        hold(bx, by);
        if (samples.splats)
          film_.Splat(x, y, value, pixels);
        else
          film_.Add(x, y, value, pixels);
      }
  }
}

Vec3 FilmTarget::Recorded(Vec3 rgb, float weight) const {
  const Vec3 value = rgb * (weight * exposure_);
  // Hue kept, as pbrt-v4's film does; NaN is left for the film to drop.
  const float largest = MaxComponent(value);
  return largest > max_component_ ? value * (max_component_ / largest) : value;
}

float FilmTarget::PixelWeight(uint32_t px, uint32_t py, float x, float y) const {
  // The masses are made once and only read after: no film lock needed.
  std::call_once(masses_prepared_, [&] { film_.PrepareMasses(); });
  return film_.PixelWeight(px, py, x, y);
}

void FilmTarget::AddPixelEstimates(const PixelWindow& window, uint32_t samples, std::span<const Vec3> values,
                                   std::span<const Vec3> variances) {
  const uint32_t width = window.x1 - window.x0;
  if (window.x1 > film_.width() || window.y1 > film_.height() || window.x0 >= window.x1 || window.y0 >= window.y1 ||
      values.size() != size_t(width) * (window.y1 - window.y0) || variances.size() != values.size())
    throw Error("pixel estimates of a window not on the film, or not one per pixel");
  const float weight = camera_weight_ * exposure_, weight_sq = weight * weight;
  std::shared_lock adding(lock_);
  for (uint32_t by = window.y0 / kBlockSide; by <= (window.y1 - 1) / kBlockSide; ++by)
    for (uint32_t bx = window.x0 / kBlockSide; bx <= (window.x1 - 1) / kBlockSide; ++bx) {
      std::lock_guard block(block_mutexes_[size_t(by) * block_columns_ + bx].mutex);
      for (uint32_t y = std::max(window.y0, by * kBlockSide); y < std::min(window.y1, (by + 1) * kBlockSide); ++y)
        for (uint32_t x = std::max(window.x0, bx * kBlockSide); x < std::min(window.x1, (bx + 1) * kBlockSide); ++x) {
          const size_t i = size_t(y - window.y0) * width + (x - window.x0);
          film_.AddEstimate(x, y, values[i] * weight, variances[i] * weight_sq, samples);
        }
    }
}

void FilmTarget::PassDone(uint32_t samples_done) {
  {
    std::lock_guard alone(lock_);
    film_.EndPass(samples_done - samples_done_);
    samples_done_ = samples_done;
  }
  on_pass_(samples_done);
}

}  // namespace yarf
