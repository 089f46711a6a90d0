// Built with -mavx2 -mfma (server/CMakeLists.txt): call only where
// LightPointKernelsAvailable() says so. The code keeps to xsimd's types and
// plain arrays, so that no inline function shared with other files is
// emitted here with AVX2 instructions.
#include "kernel/light_point_kernels.h"

#include <xsimd/xsimd.hpp>

#include "kernel/shape_surfaces.h"

namespace yarf {
namespace {

using Arch = xsimd::fma3<xsimd::avx2>;
using Floats = xsimd::batch<float, Arch>;
using Mask = xsimd::batch_bool<float, Arch>;
constexpr size_t kLanes = Floats::size;

struct Vec3s {
  Floats x, y, z;
};

Vec3s operator+(const Vec3s& a, const Vec3s& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3s operator-(const Vec3s& a, const Vec3s& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3s operator*(const Vec3s& a, const Floats& s) { return {a.x * s, a.y * s, a.z * s}; }
Floats Dot(const Vec3s& a, const Vec3s& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3s Cross(const Vec3s& a, const Vec3s& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
Vec3s Normalize(const Vec3s& v) {
  const Floats length = xsimd::sqrt(Dot(v, v));
  return {v.x / length, v.y / length, v.z / length};
}
Vec3s Broadcast(Vec3 v) { return {Floats(v.x), Floats(v.y), Floats(v.z)}; }
Floats SinFromCos(const Floats& cos_theta) {
  return xsimd::sqrt(xsimd::max(Floats(0.0f), Floats(1.0f) - cos_theta * cos_theta));
}

// One block's lanes, read from arrays of structures. Lanes past `count`
// repeat the block's first point, so that every lane computes on real data.
struct Lanes {
  alignas(32) float x[kLanes], y[kLanes], z[kLanes];

  void Gather(std::span<const Vec3> points, size_t first, size_t count) {
    for (size_t j = 0; j < kLanes; ++j) {
      const Vec3& p = points[first + (j < count ? j : 0)];
      x[j] = p.x, y[j] = p.y, z[j] = p.z;
    }
  }
  Vec3s Load() const {
    return {Floats::load_aligned(x), Floats::load_aligned(y), Floats::load_aligned(z)};
  }
  void Store(const Vec3s& v) {
    v.x.store_aligned(x), v.y.store_aligned(y), v.z.store_aligned(z);
  }
};

// uniform[3k + 1] and uniform[3k + 2] of a block's points.
struct UniformPair {
  alignas(32) float u0[kLanes], u1[kLanes];

  UniformPair(std::span<const float> uniform, size_t first, size_t count) {
    for (size_t j = 0; j < kLanes; ++j) {
      const size_t k = first + (j < count ? j : 0);
      u0[j] = uniform[3 * k + 1], u1[j] = uniform[3 * k + 2];
    }
  }
};

}  // namespace

void SampleSphereCones(const SphereGeometry& sphere, std::span<const Vec3> from, std::span<const float> uniform,
                       std::span<SurfaceSample> out) {
  constexpr float kPi = 3.14159265358979323846f;
  const float r2 = sphere.radius * sphere.radius;
  const Vec3s center = Broadcast(sphere.center);
  const Vec3s axes[3] = {Broadcast(sphere.axes[0]), Broadcast(sphere.axes[1]), Broadcast(sphere.axes[2])};
  const Floats one(1.0f), zero(0.0f);
  for (size_t first = 0; first < from.size(); first += kLanes) {
    const size_t count = std::min(kLanes, from.size() - first);
    Lanes points;
    points.Gather(from, first, count);
    const UniformPair u(uniform, first, count);
    const Vec3s p = points.Load();
    // Uniform in the cone around the direction to the centre.
    const Vec3s to_center = center - p;
    const Floats distance2 = Dot(to_center, to_center);
    const Floats cos_max = xsimd::sqrt(xsimd::max(zero, one - Floats(r2) / distance2));
    const Vec3s n = Normalize(to_center);
    // Frame(n): Duff et al.'s orthonormal basis, as the scalar Frame.
    const Floats sign = xsimd::copysign(one, n.z);
    const Floats a = Floats(-1.0f) / (sign + n.z);
    const Floats b = n.x * n.y * a;
    const Vec3s s{one + sign * n.x * n.x * a, sign * b, -(sign * n.x)};
    const Vec3s t{b, sign + n.y * n.y * a, -n.y};
    const Floats cos_theta = one - Floats::load_aligned(u.u0) * (one - cos_max);
    const Floats sin_theta = SinFromCos(cos_theta);
    const auto [sin_phi, cos_phi] = xsimd::sincos(Floats(2 * kPi) * Floats::load_aligned(u.u1));
    const Vec3s dir = s * (sin_theta * cos_phi) + t * (sin_theta * sin_phi) + n * cos_theta;
    // The near side's point along it, and its direction from the centre.
    const Floats along = Dot(dir, to_center);
    const Floats hit = along - xsimd::sqrt(xsimd::max(zero, Floats(r2) - (distance2 - along * along)));
    const Vec3s d = Normalize(p + dir * hit - center);
    // Mitsuba's uv in the sphere's own frame, as SphereUv.
    const Floats phi = xsimd::atan2(Dot(d, axes[1]), Dot(d, axes[0]));
    const Floats u_out = xsimd::select(phi < zero, phi + Floats(2 * kPi), phi) * Floats(0.5f / kPi);
    const Floats v_out = xsimd::acos(xsimd::clip(Dot(d, axes[2]), Floats(-1.0f), one)) * Floats(1 / kPi);
    const Floats pdf = one / (Floats(2 * kPi) * (one - cos_max));

    Lanes position, normal;
    position.Store(center + d * Floats(sphere.radius));
    normal.Store(sphere.flip_normals ? Vec3s{-d.x, -d.y, -d.z} : d);
    alignas(32) float us[kLanes], vs[kLanes], pdfs[kLanes];
    u_out.store_aligned(us), v_out.store_aligned(vs), pdf.store_aligned(pdfs);
    for (size_t j = 0; j < count; ++j) {
      SurfaceSample& sample = out[first + j];
      sample.position = Vec3(position.x[j], position.y[j], position.z[j]);
      sample.normal = Vec3(normal.x[j], normal.y[j], normal.z[j]);
      sample.primitive = 0;
      sample.u = us[j], sample.v = vs[j];
      sample.pdf = pdfs[j];
    }
  }
}

void SampleSphericalTriangles(std::span<const std::array<Vec3, 3>> corners, std::span<const uint32_t> triangle,
                              std::span<const Vec3> from, std::span<const float> uniform,
                              std::span<SphericalTriangleSample> out) {
  const Floats one(1.0f), zero(0.0f);
  for (size_t first = 0; first < from.size(); first += kLanes) {
    const size_t count = std::min(kLanes, from.size() - first);
    Lanes points, corner[3];
    points.Gather(from, first, count);
    for (size_t j = 0; j < kLanes; ++j) {
      const auto& v = corners[triangle[first + (j < count ? j : 0)]];
      for (int i = 0; i < 3; ++i) corner[i].x[j] = v[i].x, corner[i].y[j] = v[i].y, corner[i].z[j] = v[i].z;
    }
    const UniformPair u(uniform, first, count);
    const Vec3s p = points.Load(), v0 = corner[0].Load(), v1 = corner[1].Load(), v2 = corner[2].Load();
    // SphericalTriangle::Seen: the unit directions to the corners and the
    // solid angle (Van Oosterom & Strackee).
    const Vec3s to_a = v0 - p, to_b = v1 - p, to_c = v2 - p;
    const Mask seen = Dot(to_a, to_a) > zero && Dot(to_b, to_b) > zero && Dot(to_c, to_c) > zero;
    const Vec3s a = Normalize(to_a), b = Normalize(to_b), c = Normalize(to_c);
    const Floats ab = Dot(a, b);
    const Floats area = xsimd::select(
        seen, xsimd::abs(Floats(2.0f) * xsimd::atan2(Dot(a, Cross(b, c)), one + ab + Dot(a, c) + Dot(b, c))), zero);
    // SampleSphericalTriangle (Arvo), step for step.
    const Vec3s n_ab = Cross(a, b), n_bc = Cross(b, c), n_ca = Cross(c, a);
    Mask sampled = seen && Dot(n_ab, n_ab) > zero && Dot(n_bc, n_bc) > zero && Dot(n_ca, n_ca) > zero && area > zero;
    const Vec3s to_ab = Normalize(n_ab), to_ca = Normalize(n_ca);
    const Floats cos_alpha = xsimd::clip(-Dot(to_ab, to_ca), Floats(-1.0f), one);
    const Floats sin_alpha = xsimd::sqrt(one - cos_alpha * cos_alpha);
    const auto [sin_x, cos_x] = xsimd::sincos(Floats::load_aligned(u.u0) * area);
    const Floats sin_sub = -sin_x, cos_sub = -cos_x;
    const Floats sin_phi = sin_sub * cos_alpha - cos_sub * sin_alpha;
    const Floats cos_phi = cos_sub * cos_alpha + sin_sub * sin_alpha;
    const Floats k1 = cos_phi + cos_alpha, k2 = sin_phi - sin_alpha * ab;
    Floats cos_bp = (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha) / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha);
    cos_bp = xsimd::clip(xsimd::select(xsimd::isfinite(cos_bp), cos_bp, one), Floats(-1.0f), one);
    const Vec3s c_off_a = Normalize(c - a * Dot(c, a));
    const Vec3s cp = a * cos_bp + c_off_a * SinFromCos(cos_bp);
    const Floats cp_b = Dot(cp, b);
    const Floats cos_theta = one - Floats::load_aligned(u.u1) * (one - cp_b);
    const Vec3s across = cp - b * cp_b;
    sampled = sampled && Dot(across, across) > zero;
    const Vec3s w = b * cos_theta + Normalize(across) * SinFromCos(cos_theta);
    // Where w meets the triangle's plane (Möller–Trumbore's barycentrics).
    const Vec3s e1 = v1 - v0, e2 = v2 - v0, s1 = Cross(w, e2);
    const Floats divisor = Dot(s1, e1);
    sampled = sampled && xsimd::abs(divisor) > zero;
    const Vec3s s = p - v0;
    Floats b1 = xsimd::clip(Dot(s, s1) / divisor, zero, one);
    Floats b2 = xsimd::clip(Dot(w, Cross(s, e1)) / divisor, zero, one);
    const Floats sum = b1 + b2;
    b1 = xsimd::select(sum > one, b1 / sum, b1);
    b2 = xsimd::select(sum > one, b2 / sum, b2);

    alignas(32) float b1s[kLanes], b2s[kLanes], areas[kLanes];
    alignas(32) bool oks[kLanes];
    b1.store_aligned(b1s), b2.store_aligned(b2s), area.store_aligned(areas);
    sampled.store_aligned(oks);
    for (size_t j = 0; j < count; ++j) out[first + j] = {b1s[j], b2s[j], areas[j], oks[j]};
  }
}

}  // namespace yarf
