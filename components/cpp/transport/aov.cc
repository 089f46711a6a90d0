// aov — an arbitrary output variable: what the first surface a camera ray
// meets is, rather than the light it sends, as Mitsuba 3's `aov`
// integrator and Cycles' render passes give it. Each pixel averages its
// samples through the film's filter, as every image does, so edges blend
// (a box filter of radius 0.5 keeps them per pixel).
//
// Parameters: Aov::Parameters() below. What each value of "aov" gives
// (R, G, B of the image):
//   albedo          the directional albedo ρ(ω_o) = ∫ f |cos θ| dω of the
//                   surface's model toward the camera, estimated by one
//                   model sample per camera sample (f |cos| / pdf); what
//                   denoisers take as albedo. 1 for a white mirror.
//   sh_normal       the unit shading normal, world space (x, y, z).
//   geo_normal      the unit geometric normal, world space.
//   depth           the distance from the camera along the ray, in R, G, B.
//   position        the world-space point.
//   uv              the texture coordinates (u, v, 0).
//   shape_index     the index of the shape placement in the scene, in R, G, B.
//   material_index  the index of its material, in R, G, B.
// A ray that meets no surface reads 0, but −1 for the two indices, so
// that shape 0 and the background differ. Null boundaries (interfaces of
// media) are not surfaces: rays go on through them. Emitters, lights and
// media are not looked at.
//
// Primary sample space: 0–1 film, 2–3 lens, 4 time, 6–8 the model sample
// (albedo only).

#include <string>
#include <vector>

#include "medium_transport.h"
#include "yarf/support/wavefront.h"
#include "yarf/aov.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

// In the order of kAovNames.
enum class Variable { kAlbedo, kShadingNormal, kGeometricNormal, kDepth, kPosition, kUv, kShapeIndex, kMaterialIndex };

Variable ParseVariable(const std::string& name) {
  for (size_t i = 0; i < kAovNames.size(); ++i)
    if (name == kAovNames[i]) return Variable(i);
  throw Error("property 'aov' must be one of " + AovNameList() + ", not '" + name + "'");
}

constexpr uint32_t kModelSample = kTransportDimension;

class Aov final : public Transport {
 public:
  // Each sample lands in its own pixel: the film may be rendered in tiles.
  static std::vector<std::string> Capabilities() { return {kPixelLocalCapability}; }
  static ParameterSchema Parameters() {
    return {Parameter::String("aov")
                .Default("albedo")
                .Choices(std::vector<std::string>(kAovNames.begin(), kAovNames.end()))
                .Doc("the variable rendered")};
  }

  explicit Aov(const Properties& props) : variable_(ParseVariable(props.String("aov", "albedo"))) {}

  uint32_t Dimensions() const override { return kTransportDimension + 3; }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    const size_t n = points.Count();
    const bool indices = variable_ == Variable::kShapeIndex || variable_ == Variable::kMaterialIndex;
    std::vector<Vec3> value(n, indices ? Vec3(-1, -1, -1) : Vec3());
    const std::vector<CameraHit> hits = FirstCameraHits(scene, points, HasNullBoundaries(scene));
    if (variable_ == Variable::kAlbedo) {
      Albedos(scene, points, hits, value);
    } else {
      for (const CameraHit& first : hits) value[first.point] = Value(scene, first);
    }
    for (uint32_t i = 0; i < n; ++i) AddCameraSample(scene, points, i, value[i], out);
  }

 private:
  Vec3 Value(const SceneView& scene, const CameraHit& first) const {
    const Hit& hit = first.hit;
    switch (variable_) {
      case Variable::kShadingNormal:
        return hit.shading_normal;
      case Variable::kGeometricNormal:
        return hit.normal;
      case Variable::kDepth: {
        const float distance = Length(first.ray.origin + first.ray.direction * hit.t - first.start);
        return Vec3(distance, distance, distance);
      }
      case Variable::kPosition:
        return first.ray.origin + first.ray.direction * hit.t;
      case Variable::kUv:
        return Vec3(hit.u, hit.v, 0);
      case Variable::kShapeIndex:
        return Vec3(float(hit.shape), float(hit.shape), float(hit.shape));
      case Variable::kMaterialIndex: {
        const float material = float(scene.MaterialOf(hit.shape));
        return Vec3(material, material, material);
      }
      case Variable::kAlbedo:
        break;
    }
    return Vec3();
  }

  // One sample of each surface's model toward the camera, any lobe:
  // f |cos| / pdf, whose mean is the directional albedo.
  static void Albedos(const SceneView& scene, const PrimarySamples& points, const std::vector<CameraHit>& hits,
                      std::vector<Vec3>& value) {
    std::vector<ScatterQuery> queries(hits.size());
    for (size_t k = 0; k < hits.size(); ++k) {
      const CameraHit& first = hits[k];
      const ShadingPoint at(scene, first.hit, first.ray);
      ScatterQuery& q = queries[k];
      q.material = scene.MaterialOf(first.hit.shape);
      q.wi = at.wi;
      q.site = at.site;
      for (uint32_t j = 0; j < 3; ++j) q.uniform[j] = points.Get(first.point, kModelSample + j);
    }
    const std::vector<ScatterAnswer> answers =
        SampleSurfaces(scene, TransportMode::kRadiance, 0, queries, Densities::kForward);
    for (size_t k = 0; k < hits.size(); ++k)
      if (answers[k].flags != kScatterNone) value[hits[k].point] = answers[k].weight;
  }

  Variable variable_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::Aov>(registrar, "aov", "1.0.0",
                            "arbitrary output variables: albedo, normals, depth, position, uv, shape and "
                            "material index of the first surface");
}
