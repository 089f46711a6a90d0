// The points of surfaces at which materials, emitters and textures are
// evaluated: what a batched call knows of each point besides directions.
// Mirrors the point fields of proto/yarf/v1/surface.proto and texture.proto.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace yarf {

// Where on which shape a point lies: the hit's shape and primitive and
// the barycentrics of its triangle's second and third corners.
struct SurfaceLocation {
  uint32_t shape = 0xFFFFFFFFu;  // kNoShape: not on a shape of the scene
  uint32_t primitive = 0;
  float b1 = 0, b2 = 0;
};

// A scene's values per vertex or per face by name (Mitsuba's mesh
// attributes, "vertex_color", "face_weight"...), for textures that read
// them.
class SurfaceAttributes {
 public:
  virtual ~SurfaceAttributes() = default;
  // rgb: [N,3], attribute `name` at each location: a vertex attribute
  // interpolated, a face attribute its face's value, a one-channel one in
  // all three; 0 where the shape has no such attribute.
  // in-process only: textures read the meshes of the process they run in.
  virtual void Attribute(std::string_view name, std::span<const SurfaceLocation> at,
                         std::span<float> rgb) const = 0;
};

// N surface points. Only uv is always there; a field left empty is
// unknown to the caller (a point light, a test), and its readers fall back
// as they document.
struct SurfacePoints {
  // [N,2] texture coordinates (u, v); v = 0 is an image's top row.
  std::span<const float> uv{};
  // [N,4] the footprint: (du/dx, dv/dx, du/dy, dv/dy), the change of uv
  // from one film sample to the next; empty (or zero) for a point lookup.
  std::span<const float> footprint{};
  // [N,3] world-space positions.
  std::span<const float> position{};
  // [N,3] ∂p/∂u and ∂p/∂v in the local shading frame (+z the shading
  // normal, x along ∂p/∂u), not unit: what bump maps displace.
  std::span<const float> dpdu{}, dpdv{};
  // [N] where each point lies, and the scene's attributes there.
  std::span<const SurfaceLocation> location{};
  const SurfaceAttributes* attributes = nullptr;

  size_t Count() const { return uv.size() / 2; }
};

}  // namespace yarf
