// ambient_occlusion — ambient occlusion (pbrt-v4's AOIntegrator).
//
// At the first surface a camera ray meets, one direction over the
// hemisphere about its geometric normal turned toward the camera (pbrt-v4
// frames it by the true geometry, not the shading normal) and one
// occlusion ray, up to `maxdistance`. A pixel reads the cosine-weighted
// fraction of that hemisphere left open, (1/π)∫ V(ω) cos θ dω: 1 on an
// unoccluded surface, as pbrt's unit illuminant gives. Rays that leave the
// scene read 0; emitters, lights and the environment are not looked at.
//
// Null boundaries (interfaces of media) are not surfaces: camera rays go
// on through them, as pbrt-v4's skip surfaces without a BSDF, and so do
// occlusion rays. Media themselves are not seen (pbrt-v4's AO has no
// transmittance). Alpha cut-outs let rays through where the kernel's
// intersection says so, for both kinds of ray.
//
// Rays advance as a wavefront: one Intersect (or Occluded) batch per
// step, no SurfaceModel or Emitter calls.
//
// Primary sample space: 0–1 film, 2–3 lens, 4 time, 6–7 the direction.
//
// Parameters: AmbientOcclusion::Parameters() below.

#include <algorithm>
#include <utility>
#include <vector>

#include "medium_transport.h"
#include "yarf/support/wavefront.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

constexpr uint32_t kDirection = kTransportDimension;
// Boundaries an occlusion ray may cross before it is taken as stopped, so
// that a degenerate stack of coincident boundaries cannot stall a batch.
constexpr int kMaxCrossings = 256;

class AmbientOcclusion final : public Transport {
 public:
  // Each sample lands in its own pixel: the film may be rendered in tiles.
  static std::vector<std::string> Capabilities() { return {kPixelLocalCapability}; }
  static ParameterSchema Parameters() {
    return {
        Parameter::Bool("cossample").Default(true).Doc(
            "cosine-weighted directions; false: uniform over the hemisphere, each weighted 2 cos θ"),
        Parameter::Float("maxdistance").Min(0).Doc(
            "farthest an occluder counts, from the surface; infinity when absent"),
    };
  }

  explicit AmbientOcclusion(const Properties& props)
      : cosine_(props.Bool("cossample", true)), max_distance_(float(props.Float("maxdistance", kInfinity))) {
    if (!(max_distance_ > 0)) throw Error("property 'maxdistance' must be > 0");
  }

  uint32_t Dimensions() const override { return kTransportDimension + 2; }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    const size_t n = points.Count();
    const bool boundaries = HasNullBoundaries(scene);
    std::vector<Vec3> value(n);
    std::vector<Ray> occlusion;
    std::vector<uint32_t> owners;
    std::vector<float> weights;
    for (const CameraHit& first : FirstCameraHits(scene, points, boundaries)) {
      // The geometric normal, turned toward the camera.
      const Vec3 n = Dot(first.hit.normal, first.ray.direction) > 0 ? -first.hit.normal : first.hit.normal;
      const float u0 = points.Get(first.point, kDirection), u1 = points.Get(first.point, kDirection + 1);
      const Vec3 local = cosine_ ? SampleCosineHemisphere(u0, u1) : SampleUniformHemisphere(u0, u1);
      // cos θ/(π·pdf): 1 for cosine-weighted directions, 2 cos θ for
      // uniform ones; a grazing direction has no density and reads 0.
      const float weight = cosine_ ? 1.0f : 2 * local.z;
      if (!(local.z > 0)) continue;
      Ray ray;
      Redirect(ray, first.ray.origin + first.ray.direction * first.hit.t, n, Normalize(Frame(n).ToWorld(local)));
      ray.tfar = max_distance_;
      ray.time = first.ray.time;
      occlusion.push_back(ray);
      owners.push_back(first.point);
      weights.push_back(weight);
    }
    const std::vector<uint8_t> open = Open(scene, std::move(occlusion), boundaries);
    for (size_t k = 0; k < owners.size(); ++k)
      if (open[k]) value[owners[k]] = Vec3(weights[k], weights[k], weights[k]);
    for (uint32_t i = 0; i < n; ++i) AddCameraSample(scene, points, i, value[i], out);
  }

 private:
  // Whether each ray reaches its tfar without meeting a surface; null
  // boundaries let it through.
  static std::vector<uint8_t> Open(const SceneView& scene, std::vector<Ray> rays, bool boundaries) {
    const size_t n = rays.size();
    std::vector<uint8_t> open(n, 0);
    if (!boundaries) {
      std::vector<uint8_t> occluded(n);
      scene.Occluded(rays, occluded);
      for (size_t k = 0; k < n; ++k) open[k] = !occluded[k];
      return open;
    }
    std::vector<uint32_t> active(n);
    for (uint32_t k = 0; k < n; ++k) active[k] = k;
    for (int crossing = 0; !active.empty() && crossing <= kMaxCrossings; ++crossing) {
      std::vector<Ray> batch(active.size());
      std::vector<Hit> hits(active.size());
      for (size_t j = 0; j < active.size(); ++j) batch[j] = rays[active[j]];
      scene.Intersect(batch, hits);
      std::vector<uint32_t> next;
      for (size_t j = 0; j < active.size(); ++j) {
        if (!hits[j].Found()) {
          open[active[j]] = 1;
        } else if (IsNullBoundary(scene, hits[j].shape)) {
          rays[active[j]] = Beyond(batch[j], hits[j]);
          next.push_back(active[j]);
        }
      }
      active = std::move(next);
    }
    return open;
  }

  bool cosine_;
  float max_distance_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::AmbientOcclusion>(registrar, "ambient_occlusion", "1.0.0",
                                         "ambient occlusion: the cosine-weighted open fraction of the hemisphere");
}
