// Pinhole and thin-lens perspective cameras, the orthographic camera and
// pbrt-v4's spherical camera, placed by look-at; Mitsuba's radiance and
// irradiance meters.
#pragma once

#include <memory>
#include <string_view>

#include "kernel/shape_surfaces.h"
#include "yarf/geometry.h"
#include "yarf/v1/scene.pb.h"

namespace yarf {

class Camera {
 public:
  // Throws Error for a degenerate placement, a field of view outside (0,
  // 180), an orthographic view_size that is not positive or a meter on a
  // film other than 1×1.
  Camera(const v1::Camera& camera, uint32_t width, uint32_t height);

  // An irradiance meter's shape, in world space; its origin() becomes the
  // centre of the shape's bounds. Needed before the first Generate.
  void MeasureOn(std::shared_ptr<const ShapeSurface> surface);

  // The ray through film position (x, y) ∈ [0,1)² (x right, y down) and
  // lens position (u, v) ∈ [0,1)², in world space with a unit direction.
  // A radiance meter's is always the same; an irradiance meter's leaves a
  // point of its shape uniform in area (from film x, y) in a direction
  // cosine-distributed about the normal there (from lens u, v).
  Ray Generate(float film_x, float film_y, float lens_u, float lens_v, float time) const;
  // What each camera ray's radiance counts for on the film: π for an
  // irradiance meter (∫ L cos dω over the cosine density cos/π), else 1.
  float RayWeight() const { return kind_ == Kind::kIrradianceMeter ? kPi : 1.0f; }
  // Why light paths cannot connect to this camera (an orthographic
  // camera's rays are parallel, a meter has no lens and film to land on),
  // for the error of a method that needs them to; empty when they can.
  std::string_view UnreachableReason() const;
  // Where world point p appears on the film through lens position (u, v):
  // false when it does not (always, for an orthographic camera). Raster
  // positions in [0,1)².
  bool Connect(Vec3 p, float lens_u, float lens_v, Vec3* lens_point, float* film_x,
               float* film_y, float* importance) const;
  // 1/(A cos³θ) for a world direction leaving the lens inside the field
  // of view, 0 outside (and for an orthographic camera's delta).
  float DirectionPdf(Vec3 direction) const;
  // How far the ray of the next pixel over, in x and in y, lands from p on
  // the plane through p with normal n, taken from the lens centre toward p
  // (pbrt-v4's approximation of ray differentials at any point; exact for
  // a pinhole's first hit near the view axis). Zero when the plane is seen
  // edge-on or p is at the lens.
  void PixelSpacing(Vec3 p, Vec3 n, Vec3* dpdx, Vec3* dpdy) const;
  // The shutter's time for a uniform u: u·shutter.
  float Time(float u) const { return u * shutter_; }
  bool HasLens() const { return lens_radius_ > 0; }
  // Whether Generate's rays depend on the lens pair (a thin lens; the
  // irradiance meter's direction) and on the time (an open shutter).
  bool ReadsLens() const { return HasLens() || IsIrradianceMeter(); }
  bool ReadsTime() const { return shutter_ > 0; }
  bool IsIrradianceMeter() const { return kind_ == Kind::kIrradianceMeter; }
  Vec3 axis() const { return forward_; }
  Vec3 origin() const { return origin_; }

 private:
  enum class Kind { kPerspective, kOrthographic, kRadianceMeter, kIrradianceMeter, kSpherical };
  bool IsMeter() const { return kind_ == Kind::kRadianceMeter || kind_ == Kind::kIrradianceMeter; }
  // A spherical camera's direction through film position (x, y), camera
  // space (x right, y up, z forward).
  Vec3 SphericalDirection(float film_x, float film_y) const;
  // The point of the lens for (u, v), camera space.
  Vec3 LensPoint(float lens_u, float lens_v) const;
  Ray MeterRay(float film_x, float film_y, float lens_u, float lens_v, float time) const;

  Kind kind_ = Kind::kPerspective;
  Vec3 origin_, right_, up_, forward_;
  // Perspective: the film's half extents on the plane at distance 1;
  // orthographic: in scene units.
  float tan_half_x_ = 0, tan_half_y_ = 0;
  // The irradiance meter's shape.
  std::shared_ptr<const ShapeSurface> surface_;
  float lens_radius_ = 0, focus_distance_ = 1;
  float near_clip_ = 0, far_clip_ = 0;
  float shutter_ = 0;
  // A spherical camera's mapping: equal-area, else equirectangular.
  bool equal_area_ = true;
  // One pixel's width and height on the plane at distance 1 (a spherical
  // camera's: its angular size).
  float pixel_x_ = 0, pixel_y_ = 0;
  // 1/A, A the film's area on the plane at distance 1.
  float inv_film_area_ = 0;
};

}  // namespace yarf
