#include "kernel/camera.h"

#include <cmath>

#include "yarf/error.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {
Vec3 ToVec3(const v1::Vec3& v) { return {float(v.x()), float(v.y()), float(v.z())}; }
}  // namespace

Camera::Camera(const v1::Camera& camera, uint32_t width, uint32_t height) {
  switch (camera.model()) {
    case v1::Camera::PINHOLE:
    case v1::Camera::THIN_LENS:
      kind_ = Kind::kPerspective;
      break;
    case v1::Camera::ORTHOGRAPHIC:
      kind_ = Kind::kOrthographic;
      break;
    case v1::Camera::RADIANCE_METER:
      kind_ = Kind::kRadianceMeter;
      break;
    case v1::Camera::IRRADIANCE_METER:
      kind_ = Kind::kIrradianceMeter;
      break;
    case v1::Camera::SPHERICAL:
      kind_ = Kind::kSpherical;
      break;
    default:
      throw Error("camera: unknown model " + std::to_string(int(camera.model())));
  }
  if (!(camera.shutter() >= 0 && camera.shutter() <= 1))
    throw Error("camera: shutter must lie in [0, 1], got " + std::to_string(camera.shutter()));
  shutter_ = float(camera.shutter());
  if (IsMeter()) {
    // As Mitsuba's meters: one value, so one pixel, which every sample
    // reaches alike.
    const char* name = kind_ == Kind::kRadianceMeter ? "a radiance meter" : "an irradiance meter";
    if (width != 1 || height != 1)
      throw Error(std::string("camera: ") + name + " measures one value: its film must be 1x1, not " +
                  std::to_string(width) + "x" + std::to_string(height));
    if (kind_ == Kind::kIrradianceMeter) {
      if (camera.meter_shape().empty())
        throw Error("camera: an irradiance meter needs meter_shape, the shape it measures");
      return;
    }
    origin_ = ToVec3(camera.origin());
    const Vec3 direction = ToVec3(camera.target()) - origin_;
    if (!(Length(direction) > 0) || !std::isfinite(Length(direction)))
      throw Error("camera: a radiance meter's target must differ from its origin");
    forward_ = Normalize(direction);
    const Frame frame(forward_);
    right_ = frame.s, up_ = frame.t;
    return;
  }
  origin_ = ToVec3(camera.origin());
  const Vec3 to_target = ToVec3(camera.target()) - origin_;
  if (Length(to_target) <= 0) throw Error("camera: target equals origin");
  forward_ = Normalize(to_target);
  const Vec3 right = Cross(forward_, ToVec3(camera.up()));
  if (Length(right) <= 1e-6f) throw Error("camera: up is parallel to the view direction");
  right_ = Normalize(right);
  up_ = Cross(right_, forward_);

  if (camera.near_clip() < 0 || camera.far_clip() < 0 ||
      (camera.far_clip() > 0 && camera.far_clip() <= camera.near_clip()))
    throw Error("camera: need 0 <= near_clip < far_clip (far_clip 0 = unbounded)");
  near_clip_ = float(camera.near_clip());
  far_clip_ = float(camera.far_clip());
  if (kind_ == Kind::kSpherical) {
    if (camera.spherical_mapping() != v1::Camera::EQUAL_AREA &&
        camera.spherical_mapping() != v1::Camera::EQUIRECTANGULAR)
      throw Error("camera: unknown spherical_mapping " + std::to_string(int(camera.spherical_mapping())));
    equal_area_ = camera.spherical_mapping() == v1::Camera::EQUAL_AREA;
    // A pixel's angular size: what PixelSpacing steps by at distance 1.
    if (equal_area_) {
      pixel_x_ = pixel_y_ = std::sqrt(4 * kPi / (float(width) * float(height)));
    } else {
      pixel_x_ = 2 * kPi / float(width);
      pixel_y_ = kPi / float(height);
    }
    return;
  }
  const bool orthographic = kind_ == Kind::kOrthographic;
  if (orthographic && !(camera.view_size() > 0 && camera.view_size() < 1e30))
    throw Error("camera: an orthographic view_size must be positive and finite, got " +
                std::to_string(camera.view_size()));
  if (!orthographic && !(camera.fov() > 0 && camera.fov() < 180))
    throw Error("camera: fov must lie in (0, 180) degrees, got " + std::to_string(camera.fov()));
  const float tan_half = orthographic ? float(camera.view_size()) / 2 : std::tan(float(camera.fov()) * kPi / 360.0f);
  const float aspect = float(width) / float(height);
  bool along_x = camera.fov_axis() == v1::Camera::X;
  if (camera.fov_axis() == v1::Camera::SMALLER) along_x = width <= height;
  if (camera.fov_axis() == v1::Camera::LARGER) along_x = width > height;
  tan_half_x_ = along_x ? tan_half : tan_half * aspect;
  tan_half_y_ = along_x ? tan_half / aspect : tan_half;

  if (camera.model() == v1::Camera::THIN_LENS) {
    if (camera.lens_radius() < 0 || camera.focus_distance() <= 0)
      throw Error("camera: thin lens needs lens_radius >= 0 and focus_distance > 0");
    lens_radius_ = float(camera.lens_radius());
    focus_distance_ = float(camera.focus_distance());
  }
  inv_film_area_ = 1.0f / (4 * tan_half_x_ * tan_half_y_);
  pixel_x_ = 2 * tan_half_x_ / float(width);
  pixel_y_ = 2 * tan_half_y_ / float(height);
}

void Camera::MeasureOn(std::shared_ptr<const ShapeSurface> surface) {
  if (kind_ != Kind::kIrradianceMeter) throw Error("camera: only an irradiance meter measures on a shape");
  if (!surface || !(surface->Area() > 0)) throw Error("camera: an irradiance meter's shape has no area");
  Vec3 lower, upper;
  surface->Bounds(lower, upper);
  origin_ = (lower + upper) * 0.5f;
  surface_ = std::move(surface);
}

std::string_view Camera::UnreachableReason() const {
  switch (kind_) {
    case Kind::kOrthographic:
      return "an orthographic camera cannot be reached by light paths (its rays are parallel)";
    case Kind::kRadianceMeter:
      return "a radiance meter cannot be reached by light paths (it measures along a single ray)";
    case Kind::kIrradianceMeter:
      return "an irradiance meter cannot be reached by light paths (they land on a lens and film, and it has neither)";
    case Kind::kSpherical:
      return "a spherical camera cannot be reached by light paths (as in pbrt-v4)";
    default:
      return {};
  }
}

Ray Camera::MeterRay(float film_x, float film_y, float lens_u, float lens_v, float time) const {
  Ray ray;
  ray.time = time;
  ray.tnear = 0;
  ray.tfar = kInfinity;
  if (kind_ == Kind::kRadianceMeter) {
    ray.origin = origin_;
    ray.direction = forward_;
    return ray;
  }
  if (!surface_) throw Error("camera: the irradiance meter has no shape to measure on");
  const SurfaceSample at = surface_->SamplePoint(film_x, film_y);
  ray.direction = Frame(at.normal).ToWorld(SampleCosineHemisphere(lens_u, lens_v));
  // Off the surface, to the side the normal faces, so as not to hit it.
  ray.origin = OffsetRayOrigin(at.position, at.normal, ray.direction);
  return ray;
}

Vec3 Camera::SphericalDirection(float film_x, float film_y) const {
  if (equal_area_) {
    // The map's pole (its +z, the square's centre) is up, as pbrt-v4
    // swaps its y and z.
    const Vec3 d = EqualAreaSquareToSphere(film_x, film_y);
    return {d.x, d.z, d.y};
  }
  const float theta = kPi * film_y, phi = 2 * kPi * film_x;
  const float sin_theta = std::sin(theta);
  return {sin_theta * std::cos(phi), std::cos(theta), sin_theta * std::sin(phi)};
}

Vec3 Camera::LensPoint(float lens_u, float lens_v) const {
  if (!(lens_radius_ > 0)) return {0, 0, 0};
  const auto disk = SampleConcentricDisk(lens_u, lens_v);
  return {disk[0] * lens_radius_, disk[1] * lens_radius_, 0};
}

bool Camera::Connect(Vec3 p, float lens_u, float lens_v, Vec3* lens_point, float* film_x,
                     float* film_y, float* importance) const {
  if (!UnreachableReason().empty()) return false;
  const Vec3 lens = LensPoint(lens_u, lens_v);
  const Vec3 rel = p - origin_;
  const Vec3 local{Dot(rel, right_), Dot(rel, up_), Dot(rel, forward_)};
  if (!(local.z > near_clip_) || (far_clip_ > 0 && local.z > far_clip_)) return false;
  // The ray from the lens point through p meets the plane in focus where
  // the ray through the lens centre from film position `dir` does.
  const Vec3 to_p = local - lens;
  const float focus = lens_radius_ > 0 ? focus_distance_ : 1.0f;
  const Vec3 on_focus = lens + to_p * (focus / to_p.z);
  const float dir_x = on_focus.x / focus, dir_y = on_focus.y / focus;
  *film_x = 0.5f * (dir_x / tan_half_x_ + 1);
  *film_y = 0.5f * (1 - dir_y / tan_half_y_);
  if (!(*film_x >= 0 && *film_x < 1 && *film_y >= 0 && *film_y < 1)) return false;
  const float cos_theta = to_p.z / Length(to_p);
  *importance = inv_film_area_ / (cos_theta * cos_theta * cos_theta);
  *lens_point = origin_ + right_ * lens.x + up_ * lens.y;
  return true;
}

void Camera::PixelSpacing(Vec3 p, Vec3 n, Vec3* dpdx, Vec3* dpdy) const {
  *dpdx = *dpdy = Vec3();
  // Meters' rays carry no differentials (as Mitsuba's): the finest texture level.
  if (IsMeter()) return;
  if (kind_ == Kind::kOrthographic) {
    // Parallel rays: a pixel's step on the film, carried along the view
    // axis onto the plane.
    const float facing = Dot(n, forward_);
    if (!(std::abs(facing) > 1e-6f)) return;
    const Vec3 steps[2] = {right_ * pixel_x_, up_ * -pixel_y_};
    Vec3* out[2] = {dpdx, dpdy};
    for (int i = 0; i < 2; ++i) *out[i] = steps[i] - forward_ * (Dot(n, steps[i]) / facing);
    return;
  }
  const Vec3 rel = p - origin_;
  const float distance = Length(rel);
  if (!(distance > 0) || !std::isfinite(distance)) return;
  const Vec3 d = rel / distance;
  // Steps across d along the film's axes (along up when d is the right axis).
  Vec3 across = right_ - d * Dot(d, right_);
  if (!(Length(across) > 1e-3f)) across = up_ - d * Dot(d, up_);
  const Vec3 ex = Normalize(across), ey = Cross(d, ex);
  const float plane = Dot(n, rel);
  Vec3 landed[2];
  const Vec3 directions[2] = {d + ex * pixel_x_, d + ey * pixel_y_};
  for (int i = 0; i < 2; ++i) {
    const float cos = Dot(n, directions[i]);
    if (!(std::abs(cos) > 1e-6f)) return;
    landed[i] = directions[i] * (plane / cos) - rel;
    if (!std::isfinite(Dot(landed[i], landed[i]))) return;
  }
  *dpdx = landed[0], *dpdy = landed[1];
}

float Camera::DirectionPdf(Vec3 direction) const {
  if (!UnreachableReason().empty()) return 0;
  const Vec3 d = Normalize(direction);
  const float cos_theta = Dot(d, forward_);
  if (!(cos_theta > 0)) return 0;
  const float x = Dot(d, right_) / cos_theta, y = Dot(d, up_) / cos_theta;
  if (std::abs(x) > tan_half_x_ || std::abs(y) > tan_half_y_) return 0;
  return inv_film_area_ / (cos_theta * cos_theta * cos_theta);
}

Ray Camera::Generate(float film_x, float film_y, float lens_u, float lens_v, float time) const {
  if (IsMeter()) return MeterRay(film_x, film_y, lens_u, lens_v, time);
  if (kind_ == Kind::kSpherical) {
    const Vec3 d = SphericalDirection(film_x, film_y);
    Ray ray;
    ray.origin = origin_;
    ray.direction = Normalize(right_ * d.x + up_ * d.y + forward_ * d.z);
    ray.tnear = near_clip_;
    ray.tfar = far_clip_ > 0 ? far_clip_ : kInfinity;
    ray.time = time;
    return ray;
  }
  if (kind_ == Kind::kOrthographic) {
    Ray ray;
    ray.origin = origin_ + right_ * ((2 * film_x - 1) * tan_half_x_) + up_ * ((1 - 2 * film_y) * tan_half_y_);
    ray.direction = forward_;
    ray.tnear = near_clip_;
    ray.tfar = far_clip_ > 0 ? far_clip_ : kInfinity;
    ray.time = time;
    return ray;
  }
  // Direction in camera space (x right, y up, z forward) through the image
  // plane at z = 1.
  Vec3 dir{(2 * film_x - 1) * tan_half_x_, (1 - 2 * film_y) * tan_half_y_, 1};
  const Vec3 lens = LensPoint(lens_u, lens_v);
  if (lens_radius_ > 0) dir = dir * focus_distance_ - lens;
  const float inv_len = 1.0f / Length(dir);
  const Vec3 d = dir * inv_len;  // d.z is the cosine to the view axis
  Ray ray;
  ray.origin = origin_ + right_ * lens.x + up_ * lens.y;
  ray.direction = right_ * d.x + up_ * d.y + forward_ * d.z;
  ray.tnear = near_clip_ / d.z;
  ray.tfar = far_clip_ > 0 ? far_clip_ / d.z : kInfinity;
  ray.time = time;
  return ray;
}

}  // namespace yarf
