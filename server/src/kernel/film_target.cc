#include "kernel/film_target.h"

namespace yarf {

void FilmTarget::Accumulate(const FilmSamples& samples) {
  std::lock_guard lock(mutex_);
  for (size_t i = 0; i < samples.Count(); ++i) {
    if (samples.splats)
      film_.Splat(samples.xy[2 * i], samples.xy[2 * i + 1], samples.rgb[i]);
    else
      film_.Add(samples.xy[2 * i], samples.xy[2 * i + 1], samples.rgb[i] * camera_weight_);
  }
}

void FilmTarget::PassDone(uint32_t samples_done) {
  {
    std::lock_guard lock(mutex_);
    film_.EndPass(samples_done - samples_done_);
    samples_done_ = samples_done;
  }
  on_pass_(samples_done);
}

}  // namespace yarf
