// What every texture (textures/*.cc) does with a batch: check that the
// arrays have the shapes the interface states, and read one point's
// footprint, which may be absent.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "yarf/error.h"
#include "yarf/texture.h"

namespace yarf::textures {

// Throws unless uv is [N,2], footprint empty or [N,4], locations empty
// or [N], value [N,channels]:
// the arrays come from another process and are not trusted.
inline void CheckShapes(const SurfacePoints& at, std::span<float> value, uint32_t channels) {
  const size_t n = at.Count();
  if (at.uv.size() % 2 != 0) throw Error("texture lookup: uv must hold 2 floats per point");
  if (!at.footprint.empty() && at.footprint.size() != 4 * n)
    throw Error("texture lookup: footprint must be empty or hold 4 floats per point");
  if (!at.location.empty() && at.location.size() != n)
    throw Error("texture lookup: locations must be empty or one per point");
  if (value.size() != size_t(channels) * n)
    throw Error("texture lookup: value must hold " + std::to_string(channels) + " floats per point");
}

// Point k's (du/dx, dv/dx, du/dy, dv/dy); zero for a point lookup, and
// when one is not finite (such a point is looked up unfiltered rather
// than spreading a NaN over the image).
inline std::array<float, 4> FootprintAt(const SurfacePoints& at, size_t k) {
  std::array<float, 4> out{0, 0, 0, 0};
  if (at.footprint.empty()) return out;
  for (int i = 0; i < 4; ++i) {
    out[i] = at.footprint[4 * k + i];
    if (!std::isfinite(out[i])) return {0, 0, 0, 0};
  }
  return out;
}

}  // namespace yarf::textures
