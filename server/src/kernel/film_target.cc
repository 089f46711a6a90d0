#include "kernel/film_target.h"

namespace yarf {

void FilmTarget::Accumulate(const FilmSamples& samples) {
  std::lock_guard lock(mutex_);
  for (size_t i = 0; i < samples.Count(); ++i)
    film_.Add(samples.xy[2 * i], samples.xy[2 * i + 1], samples.rgb[i]);
}

}  // namespace yarf
