// Surface scattering and emission, mirroring proto/yarf/v1/surface.proto.
// Directions are in the local shading frame (+z = normal); wi points
// toward the camera side, wo toward where light comes from.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>

#include "yarf/component.h"
#include "yarf/surface_points.h"

namespace yarf {

// A lobe's flags: its side (reflect or refract) and its kind (diffuse,
// glossy or delta).
enum ScatterFlags : uint32_t {
  kScatterNone = 0,
  kScatterReflect = 1,
  kScatterRefract = 2,
  kScatterDelta = 4,
  kScatterDiffuse = 8,
  kScatterGlossy = 16,
  // Light passes straight on, unchanged (wo = -wi, weight 1): a surface
  // that only bounds a medium (Mitsuba's null BSDF, pbrt's interface).
  // Always with kScatterRefract | kScatterDelta, so that a method that
  // knows nothing of media treats it as a delta transmission.
  kScatterNull = 32,
};

// What a path carries: radiance from the lights (paths from the camera),
// or importance from the camera (paths from the lights). Models that
// refract scale radiance by 1/η² and importance not (Veach 1997, §5.2).
enum class TransportMode : uint32_t { kRadiance = 0, kImportance = 1 };

// Whether Sample may draw `lobe` (its ScatterFlags) under `allowed`: 0
// allows every lobe; otherwise a lobe is allowed when all its flags are,
// so kScatterReflect alone excludes a delta reflection.
inline bool LobeAllowed(uint32_t lobe, uint32_t allowed) {
  return allowed == 0 || (lobe & ~allowed) == 0;
}

class SurfaceModel : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.SurfaceModel";

  // wi, wo: [N,3] at N points; value: [N,3] = f(wi, wo) in 1/sr, no cosine.
  virtual void Evaluate(TransportMode mode, std::span<const float> wi, std::span<const float> wo,
                        const SurfacePoints& at, std::span<float> value) const = 0;
  // wi: [N,3]; uniform: [N,3] -> wo [N,3], weight [N,3]
  // (f·|cos θo|/pdf), pdf [N], flags [N] (the lobe sampled).
  virtual void Sample(TransportMode mode, std::span<const float> wi, const SurfacePoints& at,
                      std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
                      std::span<float> weight, std::span<float> pdf,
                      std::span<uint32_t> flags) const = 0;
  // pdf: [N], solid angle; 0 for delta lobes.
  virtual void Pdf(std::span<const float> wi, std::span<const float> wo,
                   const SurfacePoints& at, std::span<float> pdf) const = 0;
  virtual uint32_t Lobes() const = 0;
};

// A model made only of delta lobes (mirror, smooth glass): no finite value
// or density anywhere, so only Sample has work to do.
class DeltaSurfaceModel : public SurfaceModel {
 public:
  void Evaluate(TransportMode, std::span<const float> wi, std::span<const float> wo,
                const SurfacePoints& at, std::span<float> value) const final {
    std::fill(value.begin(), value.begin() + wi.size(), 0.0f);
  }
  void Pdf(std::span<const float> wi, std::span<const float> wo, const SurfacePoints& at,
           std::span<float> pdf) const final {
    std::fill(pdf.begin(), pdf.begin() + wi.size() / 3, 0.0f);
  }
};

// Light leaving a surface, or a point. Directions are in the emitter's
// local frame: the surface's shading frame, or a point light's own frame
// (+z its axis).
class Emitter : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Emitter";

  // w: [N,3] local direction of travel away from the emitter at N points;
  // radiance: [N,3] in W·m⁻²·sr⁻¹ (a point light: intensity, W·sr⁻¹).
  virtual void Radiance(std::span<const float> w, const SurfacePoints& at,
                        std::span<float> radiance) const = 0;
  // uniform: [N,2] -> w [N,3] local direction of emission, pdf [N] (solid
  // angle), for paths that start at the light.
  virtual void SampleDirection(std::span<const float> uniform, std::span<float> w,
                               std::span<float> pdf) const = 0;
  // pdf: [N], the solid-angle density SampleDirection has for w [N,3].
  virtual void PdfDirection(std::span<const float> w, std::span<float> pdf) const = 0;
};

}  // namespace yarf
