// Cut-outs (alpha masks) on meshes: an Embree filter function that lets a
// ray pass a hit with the probability the mesh's alpha texture gives
// there, for closest-hit and shadow rays alike (pbrt-v4's stochastic
// alpha test), so that leaves, fences and their shadows have holes.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "yarf/texture.h"

namespace yarf {

class AlphaCut {
 public:
  // `indices`: the mesh's triangles; `uvs`: its uv per vertex, or empty
  // for the barycentric parameterisation.
  AlphaCut(std::shared_ptr<const Texture> alpha, std::vector<uint32_t> indices, std::vector<float> uvs);

  // Makes this cut-out the filter of a triangle geometry of the mesh; it
  // must outlive the geometry's scene.
  void Attach(RTCGeometry geometry) const;

  // The probability that a ray meets triangle `primitive` at barycentrics
  // (b1, b2), in [0, 1].
  float Opacity(uint32_t primitive, float b1, float b2) const;

 private:
  static void Filter(const RTCFilterFunctionNArguments* args);

  TexturedValue alpha_;
  std::vector<uint32_t> indices_;
  std::vector<float> uvs_;
};

}  // namespace yarf
