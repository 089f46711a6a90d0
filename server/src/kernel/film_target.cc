#include "kernel/film_target.h"

#include <algorithm>
#include <numeric>
#include <utility>
#include <vector>

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

namespace {

// A batch's samples by the blocks their filters reach; within a block in
// batch order, so that each pixel sums them in the order it would one by one.
struct BlockGroups {
  // Per sample, the pixels its filter reaches (Film::Footprint).
  std::vector<PixelWindow> footprints;
  // The blocks reached, in block coordinates: [x0, x1) × [y0, y1).
  PixelWindow blocks{0, 0, 0, 0};
  // Per block of `blocks`, row by row, where its samples start in
  // `samples`; one more entry for the end.
  std::vector<uint32_t> starts;
  std::vector<uint32_t> samples;

  size_t Index(uint32_t bx, uint32_t by) const {
    return size_t(by - blocks.y0) * (blocks.x1 - blocks.x0) + (bx - blocks.x0);
  }
};

// By counting, not sorting: time in the samples and the blocks the batch
// reaches (a few for a tile's camera samples, at most the film's for splats).
BlockGroups GroupByBlock(const Film& film, const FilmSamples& batch, uint32_t side) {
  const uint32_t n = uint32_t(batch.Count());
  std::vector<PixelWindow> reach(n, PixelWindow{0, 0, 0, 0});
  BlockGroups groups;
  groups.footprints.resize(n);
  groups.blocks = {UINT32_MAX, UINT32_MAX, 0, 0};
  for (uint32_t i = 0; i < n; ++i) {
    const PixelWindow& pixels = groups.footprints[i] = film.Footprint(batch.xy[2 * i], batch.xy[2 * i + 1]);
    if (pixels.x0 == pixels.x1) continue;
    PixelWindow& r = reach[i];
    r = {pixels.x0 / side, pixels.y0 / side, (pixels.x1 - 1) / side + 1, (pixels.y1 - 1) / side + 1};
    groups.blocks = {std::min(groups.blocks.x0, r.x0), std::min(groups.blocks.y0, r.y0),
                     std::max(groups.blocks.x1, r.x1), std::max(groups.blocks.y1, r.y1)};
  }
  if (groups.blocks.x0 >= groups.blocks.x1) return {};
  groups.starts.assign(size_t(groups.blocks.x1 - groups.blocks.x0) * (groups.blocks.y1 - groups.blocks.y0) + 1, 0);
  const auto for_each_block = [&](const PixelWindow& r, auto&& visit) {
    for (uint32_t by = r.y0; by < r.y1; ++by)
      for (uint32_t bx = r.x0; bx < r.x1; ++bx) visit(groups.Index(bx, by));
  };
  for (const PixelWindow& r : reach) for_each_block(r, [&](size_t b) { ++groups.starts[b + 1]; });
  std::partial_sum(groups.starts.begin(), groups.starts.end(), groups.starts.begin());
  groups.samples.resize(groups.starts.back());
  std::vector<uint32_t> next(groups.starts.begin(), groups.starts.end() - 1);
  for (uint32_t i = 0; i < n; ++i) for_each_block(reach[i], [&](size_t b) { groups.samples[next[b]++] = i; });
  return groups;
}

}  // namespace

FilmTarget::FilmTarget(Film& film, FilmLock& lock, uint32_t spp, uint64_t seed, Share share,
                       const std::atomic<bool>& cancel, PassCallback on_pass)
    : film_(film), lock_(lock), spp_(spp), seed_(seed), share_(share), cancel_(cancel),
      on_pass_(std::move(on_pass)), samples_done_(share.first_sample),
      block_columns_((film.width() + kBlockSide - 1) / kBlockSide),
      block_mutexes_(std::make_unique<BlockMutex[]>(size_t(block_columns_) *
                                                    ((film.height() + kBlockSide - 1) / kBlockSide))) {}

void FilmTarget::Accumulate(const FilmSamples& samples) {
  if (samples.Count() == 0) return;
  // Without the lock: footprints depend only on the film's size and filter.
  const BlockGroups groups = GroupByBlock(film_, samples, kBlockSide);
  std::shared_lock adding(lock_);
  if (samples.splats) std::call_once(splats_prepared_, [&] { film_.PrepareSplats(); });
  for (uint32_t by = groups.blocks.y0; by < groups.blocks.y1; ++by)
    for (uint32_t bx = groups.blocks.x0; bx < groups.blocks.x1; ++bx) {
      const size_t group = groups.Index(bx, by);
      const uint32_t first = groups.starts[group], end = groups.starts[group + 1];
      if (first == end) continue;
      const PixelWindow window{bx * kBlockSide, by * kBlockSide, std::min(film_.width(), (bx + 1) * kBlockSide),
                               std::min(film_.height(), (by + 1) * kBlockSide)};
      std::lock_guard block(block_mutexes_[size_t(by) * block_columns_ + bx].mutex);
      for (uint32_t k = first; k < end; ++k) {
        const uint32_t i = groups.samples[k];
        const float x = samples.xy[2 * i], y = samples.xy[2 * i + 1];
        // The sample's pixels in this block.
        const PixelWindow& footprint = groups.footprints[i];
        const PixelWindow pixels{std::max(footprint.x0, window.x0), std::max(footprint.y0, window.y0),
                                 std::min(footprint.x1, window.x1), std::min(footprint.y1, window.y1)};
        if (samples.splats)
          film_.Splat(x, y, samples.rgb[i], pixels);
        else
          film_.Add(x, y, samples.rgb[i] * camera_weight_, pixels);
      }
    }
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
  const float weight_sq = camera_weight_ * camera_weight_;
  std::shared_lock adding(lock_);
  for (uint32_t by = window.y0 / kBlockSide; by <= (window.y1 - 1) / kBlockSide; ++by)
    for (uint32_t bx = window.x0 / kBlockSide; bx <= (window.x1 - 1) / kBlockSide; ++bx) {
      std::lock_guard block(block_mutexes_[size_t(by) * block_columns_ + bx].mutex);
      for (uint32_t y = std::max(window.y0, by * kBlockSide); y < std::min(window.y1, (by + 1) * kBlockSide); ++y)
        for (uint32_t x = std::max(window.x0, bx * kBlockSide); x < std::min(window.x1, (bx + 1) * kBlockSide); ++x) {
          const size_t i = size_t(y - window.y0) * width + (x - window.x0);
          film_.AddEstimate(x, y, values[i] * camera_weight_, variances[i] * weight_sq, samples);
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
