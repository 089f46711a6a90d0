#include "kernel/shape_surfaces.h"

#include <algorithm>
#include <cmath>

#include "kernel/light_point_kernels.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// Area density `pdf_area` at surface point `at` turned into solid angle
// at p; 0 when the surface is seen edge-on or p lies on it.
float AreaToSolidAngle(float pdf_area, Vec3 p, const SurfaceSample& at) {
  const Vec3 d = at.position - p;
  const float d2 = Dot(d, d);
  const float cos_at = std::abs(Dot(at.normal, d));
  return cos_at > 0 && d2 > 0 ? pdf_area * d2 * std::sqrt(d2) / cos_at : 0.0f;
}

// Unit direction d from a sphere's centre in the sphere's own frame
// (`axes`), and its texture coordinates there (those SphereParameters gives).
Vec3 SphereUv(const std::array<Vec3, 3>& axes, Vec3 d, float& u, float& v) {
  const Vec3 local(Dot(d, axes[0]), Dot(d, axes[1]), Dot(d, axes[2]));
  float phi = std::atan2(local.y, local.x);
  if (phi < 0) phi += 2 * kPi;
  u = phi * (0.5f * kInvPi);
  v = std::acos(std::clamp(local.z, -1.0f, 1.0f)) * kInvPi;
  return local;
}

}  // namespace

// Here, not beside the kernels, which are built for AVX2 throughout.
bool LightPointKernelsAvailable() {
  static const bool available = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return available;
}

void SphereParameters(const std::array<Vec3, 3>& axes, Vec3 d, float r, Hit& hit) {
  const Vec3 local = SphereUv(axes, d, hit.u, hit.v);
  const float cos_theta = std::clamp(local.z, -1.0f, 1.0f), sin_theta = std::sqrt(1 - cos_theta * cos_theta);
  // cos φ and sin φ from the direction itself, without trigonometry; at
  // the poles φ = 0, as atan2(0, 0) gives.
  const float rho = std::sqrt(local.x * local.x + local.y * local.y);
  const float cos_phi = rho > 0 ? local.x / rho : 1.0f, sin_phi = rho > 0 ? local.y / rho : 0.0f;
  const Vec3 along_phi = axes[0] * (-local.y) + axes[1] * local.x;
  const Vec3 along_theta = axes[0] * (cos_theta * cos_phi) + axes[1] * (cos_theta * sin_phi) - axes[2] * sin_theta;
  hit.dpdu = along_phi * (2 * kPi * r);
  hit.dpdv = along_theta * (kPi * r);
}

// Sphere

void SphereSurface::Bounds(Vec3& lower, Vec3& upper) const {
  const Vec3 r(sphere_.radius, sphere_.radius, sphere_.radius);
  lower = sphere_.center - r;
  upper = sphere_.center + r;
}

float SphereSurface::Area() const { return 4 * kPi * sphere_.radius * sphere_.radius; }

SurfaceSample SpherePointAt(const SphereGeometry& sphere, Vec3 d) {
  SurfaceSample s;
  s.position = sphere.center + d * sphere.radius;
  s.normal = sphere.flip_normals ? -d : d;
  SphereUv(sphere.axes, d, s.u, s.v);
  return s;
}

SurfaceSample SampleSphereCone(const SphereGeometry& sphere, Vec3 p, float u0, float u1) {
  // Uniform in the cone, then the point the direction meets on the near
  // side.
  const float r2 = sphere.radius * sphere.radius;
  const Vec3 to_center = sphere.center - p;
  const float distance2 = Dot(to_center, to_center);
  const float cos_max = std::sqrt(std::max(0.0f, 1 - r2 / distance2));
  const Vec3 dir = Frame(Normalize(to_center)).ToWorld(SampleUniformCone(u0, u1, cos_max));
  const float b = Dot(dir, to_center);
  const float t = b - std::sqrt(std::max(0.0f, r2 - (distance2 - b * b)));
  SurfaceSample s = SpherePointAt(sphere, Normalize(p + dir * t - sphere.center));
  s.pdf = UniformConePdf(1, cos_max);
  return s;
}

SurfaceSample SphereSurface::At(Vec3 d) const { return SpherePointAt(sphere_, d); }

bool SphereSurface::SeenByCone(Vec3 p) const {
  // From just outside, the cone is too ill-conditioned to be worth it.
  const Vec3 d = sphere_.center - p;
  return by_cone_ && Dot(d, d) > sphere_.radius * sphere_.radius * 1.0001f;
}

void SphereSurface::Sample(std::span<const float> uniform, std::span<SurfaceSample> out) const {
  for (size_t k = 0; k < out.size(); ++k) {
    out[k] = At(SampleUniformSphere(uniform[3 * k + 1], uniform[3 * k + 2]));
    out[k].pdf = 1 / Area();
  }
}

void SphereSurface::Sample(std::span<const Vec3> from, std::span<const float> uniform,
                           std::span<SurfaceSample> out) const {
  // Every point by cone, eight at a time where the CPU can; those that do
  // not see the sphere by cone are redrawn below.
  const bool batched = by_cone_ && LightPointKernelsAvailable();
  if (batched) SampleSphereCones(sphere_, from.first(out.size()), uniform, out);
  for (size_t k = 0; k < out.size(); ++k) {
    const Vec3 p = from[k];
    const float u0 = uniform[3 * k + 1], u1 = uniform[3 * k + 2];
    if (!SeenByCone(p)) {
      out[k] = At(SampleUniformSphere(u0, u1));
      out[k].pdf = AreaToSolidAngle(1 / Area(), p, out[k]);
    } else if (!batched) {
      out[k] = SampleSphereCone(sphere_, p, u0, u1);
    }
  }
}

void SphereSurface::Pdf(std::span<const Vec3> from, std::span<const SurfaceSample> at, std::span<float> pdf) const {
  const float r2 = sphere_.radius * sphere_.radius;
  for (size_t k = 0; k < pdf.size(); ++k) {
    const Vec3 p = from[k];
    if (!SeenByCone(p)) {
      // The normal is the sphere's own at the point.
      SurfaceSample on = at[k];
      on.normal = Normalize(on.position - sphere_.center);
      pdf[k] = AreaToSolidAngle(1 / Area(), p, on);
      continue;
    }
    const Vec3 to_center = sphere_.center - p;
    pdf[k] = UniformConePdf(1, std::sqrt(std::max(0.0f, 1 - r2 / Dot(to_center, to_center))));
  }
}

SurfaceSample SphereSurface::SamplePoint(float u0, float u1) const {
  // One primitive: both numbers place the point.
  SurfaceSample s = At(SampleUniformSphere(u0, u1));
  s.pdf = 1 / Area();
  return s;
}

SurfaceSample SphereSurface::Gathered(Vec3 seen_from, float& area) const {
  const Vec3 to = seen_from - sphere_.center;
  area = kPi * sphere_.radius * sphere_.radius;
  return At(Length(to) > 0 ? Normalize(to) : Vec3(0, 0, 1));
}

// Triangle mesh

MeshSurface::MeshSurface(std::vector<std::array<Vec3, 3>> corners, std::vector<Vec3> normals,
                         const TriangleMesh& mesh, bool by_solid_angle)
    : corners_(std::move(corners)), normals_(std::move(normals)), mesh_(&mesh), by_solid_angle_(by_solid_angle) {
  if (corners_.empty() || corners_.size() != normals_.size()) throw Error("a mesh surface needs its triangles");
  cdf_.reserve(corners_.size());
  double running = 0;
  for (const auto& v : corners_) {
    running += 0.5 * Length(Cross(v[1] - v[0], v[2] - v[0]));
    cdf_.push_back(float(running));
  }
  area_ = float(running);
  // The area-weighted centroid and normal sum, once: LightPoint gathers the
  // surface into them for every point it lights.
  for (size_t t = 0; t < corners_.size(); ++t) {
    const float a = Share(uint32_t(t));
    centroid_ += (corners_[t][0] + corners_[t][1] + corners_[t][2]) * (a / 3);
    normal_sum_ += normals_[t] * a;
  }
}

void MeshSurface::Bounds(Vec3& lower, Vec3& upper) const {
  lower = upper = corners_[0][0];
  for (const auto& triangle : corners_)
    for (const Vec3 v : triangle) {
      lower = Vec3(std::min(lower.x, v.x), std::min(lower.y, v.y), std::min(lower.z, v.z));
      upper = Vec3(std::max(upper.x, v.x), std::max(upper.y, v.y), std::max(upper.z, v.z));
    }
}

float MeshSurface::Share(uint32_t t) const {
  return area_ > 0 ? (cdf_[t] - (t > 0 ? cdf_[t - 1] : 0.0f)) / area_ : 0.0f;
}

uint32_t MeshSurface::Pick(float& u, float& share) const {
  const auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u * area_);
  const uint32_t t = uint32_t((it == cdf_.end() ? cdf_.end() - 1 : it) - cdf_.begin());
  share = Share(t);
  // u's place within triangle t's stretch of the running sum, rescaled
  // to [0,1); a float keeps fewer bits of it the more triangles there are.
  const float below = t > 0 ? cdf_[t - 1] : 0.0f, width = cdf_[t] - below;
  u = width > 0 ? std::clamp((u * area_ - below) / width, 0.0f, std::nextafter(1.0f, 0.0f)) : 0.5f;
  return t;
}

bool MeshSurface::SampledBySolidAngle(float solid_angle) {
  // pbrt-v4's bounds: below, area sampling is as good and cheaper; above,
  // the spherical triangle is too close to a hemisphere to sample well.
  constexpr float kMinSolidAngle = 3e-4f, kMaxSolidAngle = 6.22f;
  return solid_angle > kMinSolidAngle && solid_angle < kMaxSolidAngle;
}

bool MeshSurface::BySolidAngle(uint32_t t, Vec3 p, SphericalTriangle& seen) const {
  if (!by_solid_angle_) return false;
  seen = SphericalTriangle::Seen(corners_[t].data(), p);
  return SampledBySolidAngle(seen.area);
}

void MeshSurface::At(uint32_t t, const std::array<float, 3>& b, SurfaceSample& out) const {
  const auto& v = corners_[t];
  out.position = v[0] * b[0] + v[1] * b[1] + v[2] * b[2];
  out.normal = normals_[t];
  out.primitive = t;
  float uv[2];
  TriangleUvAt(mesh_->indices, mesh_->uvs, t, b[1], b[2], uv);
  out.u = uv[0], out.v = uv[1];
}

void MeshSurface::Sample(std::span<const float> uniform, std::span<SurfaceSample> out) const {
  for (size_t k = 0; k < out.size(); ++k) out[k] = SamplePoint(uniform[3 * k + 1], uniform[3 * k + 2]);
}

void MeshSurface::Sample(std::span<const Vec3> from, std::span<const float> uniform,
                         std::span<SurfaceSample> out) const {
  if (by_solid_angle_ && LightPointKernelsAvailable()) return SampleBatched(from, uniform, out);
  for (size_t k = 0; k < out.size(); ++k) {
    const Vec3 p = from[k];
    float u0 = uniform[3 * k + 1], share = 0;
    const float u1 = uniform[3 * k + 2];
    const uint32_t t = Pick(u0, share);
    std::array<float, 3> b;
    SphericalTriangle seen;
    if (BySolidAngle(t, p, seen) && SampleSphericalTriangle(corners_[t].data(), p, seen, u0, u1, b)) {
      At(t, b, out[k]);
      out[k].pdf = share / seen.area;
      continue;
    }
    SampleByArea(t, p, u0, u1, out[k]);
  }
}

void MeshSurface::SampleBatched(std::span<const Vec3> from, std::span<const float> uniform,
                                std::span<SurfaceSample> out) const {
  const size_t n = out.size();
  std::vector<uint32_t> triangle(n);
  std::vector<float> share(n), u(uniform.begin(), uniform.begin() + 3 * n);
  for (size_t k = 0; k < n; ++k) triangle[k] = Pick(u[3 * k + 1], share[k]);
  std::vector<SphericalTriangleSample> seen(n);
  SampleSphericalTriangles(corners_, triangle, from.first(n), u, seen);
  for (size_t k = 0; k < n; ++k) {
    const SphericalTriangleSample& s = seen[k];
    if (s.sampled && SampledBySolidAngle(s.solid_angle)) {
      At(triangle[k], {1 - s.b1 - s.b2, s.b1, s.b2}, out[k]);
      out[k].pdf = share[k] / s.solid_angle;
      continue;
    }
    SampleByArea(triangle[k], from[k], u[3 * k + 1], u[3 * k + 2], out[k]);
  }
}

void MeshSurface::SampleByArea(uint32_t t, Vec3 p, float u0, float u1, SurfaceSample& out) const {
  At(t, SampleUniformTriangle(u0, u1), out);
  out.pdf = AreaToSolidAngle(1 / area_, p, out);
}

void MeshSurface::Pdf(std::span<const Vec3> from, std::span<const SurfaceSample> at, std::span<float> pdf) const {
  for (size_t k = 0; k < pdf.size(); ++k) {
    const uint32_t t = at[k].primitive;
    if (t >= corners_.size()) {
      pdf[k] = 0;
      continue;
    }
    SphericalTriangle seen;
    if (BySolidAngle(t, from[k], seen)) {
      pdf[k] = Share(t) / seen.area;
      continue;
    }
    SurfaceSample on = at[k];
    on.normal = normals_[t];
    pdf[k] = AreaToSolidAngle(1 / area_, from[k], on);
  }
}

SurfaceSample MeshSurface::SamplePoint(float u0, float u1) const {
  float share = 0;
  const uint32_t t = Pick(u0, share);
  SurfaceSample s;
  At(t, SampleUniformTriangle(u0, u1), s);
  s.pdf = 1 / area_;
  return s;
}

SurfaceSample MeshSurface::Gathered(Vec3, float& area) const {
  SurfaceSample s;
  s.position = centroid_;
  s.normal = Length(normal_sum_) > 0 ? Normalize(normal_sum_) : normals_[0];
  area = area_;
  return s;
}

bool MeshSurface::NormalCone(Vec3& axis, float& cos_theta) const {
  if (!(Length(normal_sum_) > 0.5f)) return false;
  axis = Normalize(normal_sum_);
  cos_theta = 1;
  for (const Vec3 n : normals_) cos_theta = std::min(cos_theta, Dot(axis, n));
  // Less a little for the rounding of the normals.
  cos_theta = std::max(-1.0f, cos_theta - 1e-4f);
  return cos_theta > -1;
}

}  // namespace yarf
