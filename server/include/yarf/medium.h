// Participating media, mirroring proto/yarf/v1/medium.proto: the
// coefficients of the radiative transfer equation at points, majorants
// along rays for null-scattering tracking (Miller et al. 2019, as pbrt-v4's
// VolPathIntegrator uses them), and the medium's phase function.
//
// Everything is in world space: a medium places itself (a grid by its own
// to_world). Coefficients are per unit length of the scene, RGB.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "yarf/component.h"
#include "yarf/vecmath.h"

namespace yarf {

// No medium: vacuum.
inline constexpr uint32_t kNoMedium = 0xFFFFFFFFu;

// The media on either side of a surface: the interior lies against its
// normal, the exterior on its side. A surface that is no boundary leaves
// a ray in the medium it was in.
struct MediumInterface {
  uint32_t interior = kNoMedium, exterior = kNoMedium;
  bool boundary = false;

  // The medium a ray in `current` is in after crossing the surface (or
  // leaving it) toward `direction`, the surface's geometric normal `normal`.
  uint32_t Beyond(Vec3 direction, Vec3 normal, uint32_t current) const {
    if (!boundary) return current;
    return Dot(direction, normal) > 0 ? exterior : interior;
  }
};

// A stretch [t0, t1) of a ray over which the medium's extinction σ_t
// never exceeds sigma_maj (per channel).
struct MajorantSegment {
  float t0 = 0, t1 = 0;
  Vec3 sigma_maj;
};

// The majorant segments of a batch of rays: ray i owns
// segments[offsets[i]] .. segments[offsets[i + 1] - 1], in increasing t,
// not overlapping; where a ray has no segment the medium is empty.
struct MajorantSegments {
  std::vector<MajorantSegment> segments;
  std::vector<uint32_t> offsets;  // N + 1

  void Clear() {
    segments.clear();
    offsets.assign(1, 0);
  }
  std::span<const MajorantSegment> Of(size_t ray) const {
    return {segments.data() + offsets[ray], segments.data() + offsets[ray + 1]};
  }
};

class Medium : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Medium";

  // origin, direction: [N,3] (direction unit); tmax: [N]. Replaces `out`
  // with the majorant segments of each ray over [0, tmax[i]).
  virtual void Majorants(std::span<const float> origin, std::span<const float> direction,
                         std::span<const float> tmax, MajorantSegments& out) const = 0;
  // position: [N,3] -> sigma_a, sigma_s: [N,3] absorption and scattering
  // coefficients; emission: [N,3] the radiance the medium emits where it
  // absorbs (pbrt's Le: the source term is σ_a·Le), zero when it does not.
  virtual void Coefficients(std::span<const float> position, std::span<float> sigma_a,
                            std::span<float> sigma_s, std::span<float> emission) const = 0;
  // Whether Coefficients may ever report emission (so that transports can
  // skip looking for it).
  virtual bool Emits() const = 0;
  // The phase function p(wi, wo) (1/sr, integrating to 1 over wo) at
  // `position`: wi points back toward where the path came from, wo toward
  // where light comes from, both away from the point (forward scattering
  // is wo = -wi). wi, wo, position: [N,3] -> value, pdf: [N].
  virtual void EvaluatePhase(std::span<const float> wi, std::span<const float> wo,
                             std::span<const float> position, std::span<float> value,
                             std::span<float> pdf) const = 0;
  // wi, position: [N,3], uniform: [N,2] -> wo: [N,3], weight: [N]
  // (p/pdf), pdf: [N].
  virtual void SamplePhase(std::span<const float> wi, std::span<const float> position,
                           std::span<const float> uniform, std::span<float> wo, std::span<float> weight,
                           std::span<float> pdf) const = 0;
};

}  // namespace yarf
