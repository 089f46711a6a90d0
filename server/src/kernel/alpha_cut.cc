#include "kernel/alpha_cut.h"

#include <bit>

#include "kernel/mesh_io.h"
#include "yarf/support/hash.h"

namespace yarf {

AlphaCut::AlphaCut(std::shared_ptr<const Texture> alpha, std::vector<uint32_t> indices, std::vector<float> uvs)
    : alpha_(TexturedValue(std::move(alpha)).Clamped(0.0f, 1.0f)), indices_(std::move(indices)), uvs_(std::move(uvs)) {}

void AlphaCut::Attach(RTCGeometry geometry) const {
  rtcSetGeometryUserData(geometry, const_cast<AlphaCut*>(this));
  rtcSetGeometryIntersectFilterFunction(geometry, &AlphaCut::Filter);
  rtcSetGeometryOccludedFilterFunction(geometry, &AlphaCut::Filter);
}

float AlphaCut::Opacity(uint32_t primitive, float b1, float b2) const {
  float uv[2];
  TriangleUvAt(indices_, uvs_, primitive, b1, b2, uv);
  return alpha_.FloatsAt(SurfacePoints{.uv = uv})[0];
}

void AlphaCut::Filter(const RTCFilterFunctionNArguments* args) {
  const auto* cut = static_cast<const AlphaCut*>(args->geometryUserPtr);
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] != -1) continue;
    const uint32_t primitive = RTCHitN_primID(args->hit, n, i);
    const float alpha = cut->Opacity(primitive, RTCHitN_u(args->hit, n, i), RTCHitN_v(args->hit, n, i));
    if (alpha >= 1) continue;
    // A hash of the ray, so that each test of one ray at one point agrees.
    const auto bits = [](float x) { return std::bit_cast<uint32_t>(x); };
    const uint64_t h = Hash(bits(RTCRayN_org_x(args->ray, n, i)), bits(RTCRayN_org_y(args->ray, n, i)),
                            bits(RTCRayN_org_z(args->ray, n, i)), bits(RTCRayN_dir_x(args->ray, n, i)),
                            bits(RTCRayN_dir_y(args->ray, n, i)), bits(RTCRayN_dir_z(args->ray, n, i)), primitive);
    if (!(ToUnitFloat(uint32_t(h >> 32)) < alpha)) args->valid[i] = 0;
  }
}

}  // namespace yarf
