// Pinhole and thin-lens perspective cameras placed by look-at.
#pragma once

#include "yarf/geometry.h"
#include "yarf/v1/scene.pb.h"

namespace yarf {

class Camera {
 public:
  // Throws Error for a degenerate placement or a field of view outside (0, 180).
  Camera(const v1::Camera& camera, uint32_t width, uint32_t height);

  // The ray through film position (x, y) ∈ [0,1)² (x right, y down) and
  // lens position (u, v) ∈ [0,1)², in world space with a unit direction.
  Ray Generate(float film_x, float film_y, float lens_u, float lens_v) const;

 private:
  Vec3 origin_, right_, up_, forward_;
  float tan_half_x_ = 0, tan_half_y_ = 0;
  float lens_radius_ = 0, focus_distance_ = 1;
  float near_clip_ = 0, far_clip_ = 0;
};

}  // namespace yarf
