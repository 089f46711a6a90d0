// Where a solid texture (solid_noise.cc, checkerboard3d.cc) looks up: a
// point's world position (SurfacePoints::position) carried into the
// texture's own space by its `to_texture`; the origin's image where the
// position is not known (a point on a light, seen by its uv).
#pragma once

#include <cmath>
#include <cstddef>

#include "yarf/error.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/surface_points.h"
#include "yarf/vecmath.h"

namespace yarf::textures {

class TextureSpace {
 public:
  static Parameter ToTextureParameter() {
    return Parameter::Matrix("to_texture").Doc("world space to the texture's space (identity when absent)");
  }

  explicit TextureSpace(const Properties& props) : to_texture_(props.Matrix("to_texture", Transform::Identity())) {
    for (const double x : to_texture_.m)
      if (!std::isfinite(x)) throw Error("property 'to_texture' must be finite");
  }

  // Point k of `at`, in the texture's space.
  Vec3 At(const SurfacePoints& at, size_t k) const {
    const bool positioned = at.position.size() == 3 * at.Count();
    return to_texture_.Point(positioned ? Vec3::Load(&at.position[3 * k]) : Vec3(0, 0, 0));
  }

 private:
  Transform to_texture_;
};

}  // namespace yarf::textures
