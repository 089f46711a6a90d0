// roughdielectric — rough glass (GGX microfacets, reflection and refraction)
//
// A rough boundary between the exterior medium (ext_ior, the +z side) and
// the interior one (int_ior, the -z side), made of smooth dielectric
// microfacets with GGX normals (Walter et al., "Microfacet models for
// refraction through rough surfaces", EGSR 2007). With η the index of wo's
// side over wi's side (1 for a reflection), the generalised half vector
// m ∝ wi + η wo (flipped to m.z > 0), F the Fresnel reflectance at wi·m,
// D the GGX distribution and G2 Smith's height-correlated
// masking-shadowing (microfacet.h):
//
//   reflection (wi, wo on one side):
//     f = F · D · G2 / (4 |cos θi| |cos θo|)
//   refraction (wi, wo on opposite sides), for radiance:
//     f = |wi·m| |wo·m| (1 - F) D G2 / (|cos θi| |cos θo| (wi·m + η wo·m)²)
//
// Walter's eq. 21 divided by η²: radiance refracted into a denser medium is
// compressed into a smaller solid angle (as dielectric.cc). Paths carrying
// importance (TransportMode::kImportance, from the lights) refract
// without that factor: their f is the radiance f times η², which makes
// f_importance(wi, wo) = f_radiance(wo, wi) (Veach 1997, §5.2). Both sides
// scatter (wi.z < 0 means the ray arrives from inside); microfacets
// facing away from wi or wo contribute nothing.
//
// Parameters: RoughDielectric::Parameters() below; the indices' defaults
// are BK7 glass inside and air outside. They must differ: matched indices
// make the interface a delta pass-through (use `dielectric`). A texture's
// α is clamped to ≥ 10⁻⁴ (microfacet.h).
//
// Lobes: glossy reflection and glossy refraction. Sample draws a normal m
// from the normals visible from wi (Heitz, JCGT 2018), then reflects with
// probability F(wi·m) and refracts otherwise, so the weight is G2 / G1(wi)
// for a reflection and G2 / (G1(wi) η²) for a refraction of radiance (G2
// / G1(wi) for importance). When `allowed` excludes a lobe, the other is
// drawn always and its weight carries its Fresnel factor. Normals that
// send wo to the wrong side give no sample.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "microfacet.h"
#include "yarf/support/scatter_rows.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;
namespace mf = yarf::microfacet;

constexpr uint32_t kReflectLobe = yarf::kScatterReflect | yarf::kScatterGlossy;
constexpr uint32_t kRefractLobe = yarf::kScatterRefract | yarf::kScatterGlossy;

float RequireDistinctIndices(float eta) {
  if (eta == 1.0f)
    throw yarf::Error("properties 'int_ior' and 'ext_ior' must differ: matched indices make "
                      "the rough interface invisible (use 'dielectric', which passes light "
                      "straight through)");
  return eta;
}

class RoughDielectric final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    return yarf::JoinParameters({
        yarf::RelativeIndexParameters(1.5046, 1.000277),
        mf::RoughnessParameters(0.1, /*anisotropic=*/true, /*textured=*/true),
    });
  }

  explicit RoughDielectric(const yarf::Properties& props)
      : eta_(RequireDistinctIndices(yarf::ReadRelativeIndex(props, 1.5046, 1.000277))),
        roughness_(mf::ReadTexturedRoughness(props, 0.1, /*anisotropic=*/true)) {}

  void Evaluate(yarf::TransportMode mode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const auto roughness = roughness_.At(at);
    yarf::EvaluateEach(wi, wo, value, [&](size_t k, Vec3 in, Vec3 out) {
      Local local;
      const float f = At(roughness[k], in, out, &local) ? Value(local, mode) : 0.0f;
      return Vec3(f, f, f);
    });
  }

  void Sample(yarf::TransportMode mode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_reflect = yarf::LobeAllowed(kReflectLobe, allowed);
    const bool can_refract = yarf::LobeAllowed(kRefractLobe, allowed);
    const auto roughnesses = roughness_.At(at);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const mf::Roughness roughness = roughnesses[k];
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float* u = &uniform[3 * k];
      Vec3 out;
      Local local;
      bool reflect = false, found = false;
      if ((can_reflect || can_refract) && in.z != 0) {
        // Normals visible from wi's side: those of -wi when it lies below.
        const Vec3 seen_from = in.z > 0 ? in : -in;
        const Vec3 m = mf::SampleVisibleNormal(seen_from, roughness, u[1], u[2]);
        const float fresnel = yarf::FresnelDielectric(yarf::Dot(in, m), eta_);
        const float reflect_share = can_reflect ? fresnel : 0.0f;
        const float total = reflect_share + (can_refract ? 1.0f - fresnel : 0.0f);
        reflect = uniform[3 * k] * total < reflect_share;
        if (total > 0) {
          if (reflect) {
            out = mf::ReflectAbout(in, m);
            found = out.z * in.z > 0;
          } else {
            found = mf::RefractAbout(in, m, eta_, &out) && out.z * in.z < 0;
          }
        }
        // Density and value from (wi, wo), as Pdf and Evaluate see them.
        found = found && At(roughness, in, out, &local) && local.reflect == reflect;
      }
      float density = 0;
      if (found) {
        const float reflect_share = can_reflect ? local.fresnel : 0.0f;
        const float refract_share = can_refract ? 1.0f - local.fresnel : 0.0f;
        const float total = reflect_share + refract_share;
        if (total > 0) density = local.density * (reflect ? reflect_share : refract_share) / total;
      }
      if (!(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      const float w = Value(local, mode) * std::abs(out.z) / density;
      rows.Store(k, out, Vec3(w, w, w), density, reflect ? kReflectLobe : kRefractLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    const auto roughness = roughness_.At(at);
    yarf::PdfEach(wi, wo, pdf, [&](size_t k, Vec3 in, Vec3 out) {
      Local local;
      return At(roughness[k], in, out, &local)
                 ? local.density * (local.reflect ? local.fresnel : 1.0f - local.fresnel)
                 : 0.0f;
    });
  }

  uint32_t Lobes() const override { return kReflectLobe | kRefractLobe; }

 private:
  // What f and the density of a pair (wi, wo) are made of.
  struct Local {
    bool reflect = false;
    float eta = 1;       // index of wo's side over wi's side (1 for a reflection)
    float fresnel = 0;   // F(wi·m)
    float density = 0;   // of wo given the microfacet: D_wi(m) times the Jacobian dm/dwo
    float geometry = 0;  // D(m) G2 |wi·m| |wo·m| / (|cos θi| |cos θo|), for f
    float jacobian = 0;  // 1 / (4 |wi·m| |wo·m|) or 1 / (wi·m + η wo·m)², for f
  };

  // The microfacet that scatters wi into wo, and what it contributes.
  // False when there is none (grazing directions, a microfacet facing away
  // from wi or wo).
  bool At(mf::Roughness roughness, Vec3 wi, Vec3 wo, Local* out) const {
    if (wi.z == 0 || wo.z == 0) return false;
    Local l;
    l.reflect = wi.z * wo.z > 0;
    l.eta = l.reflect ? 1.0f : (wi.z > 0 ? eta_ : 1.0f / eta_);
    Vec3 m = wi + wo * l.eta;
    const float length = yarf::Length(m);
    if (!(length > 0)) return false;
    m = m / length;
    if (m.z < 0) m = -m;
    const float cos_im = yarf::Dot(wi, m), cos_om = yarf::Dot(wo, m);
    if (cos_im * wi.z <= 0 || cos_om * wo.z <= 0) return false;
    const float d = mf::Ndf(m, roughness);
    const float visible = mf::SmithG1(wi, roughness) * std::abs(cos_im) * d / std::abs(wi.z);
    if (l.reflect) {
      l.jacobian = 1.0f / (4.0f * std::abs(cos_im) * std::abs(cos_om));
      // dm/dwo = 1 / (4 |wo·m|).
      l.density = visible / (4.0f * std::abs(cos_om));
    } else {
      const float denominator = cos_im + l.eta * cos_om;
      l.jacobian = 1.0f / (denominator * denominator);
      // dm/dwo = η² |wo·m| / (wi·m + η wo·m)² (Walter et al., eq. 17).
      l.density = visible * l.eta * l.eta * std::abs(cos_om) * l.jacobian;
    }
    l.fresnel = yarf::FresnelDielectric(cos_im, eta_);
    l.geometry = d * mf::SmithG2(wi, wo, roughness) *
                 std::abs(cos_im) * std::abs(cos_om) / (std::abs(wi.z) * std::abs(wo.z));
    *out = l;
    return true;
  }

  static float Value(const Local& l, yarf::TransportMode mode) {
    if (l.reflect) return l.fresnel * l.geometry * l.jacobian;
    const float f = (1.0f - l.fresnel) * l.geometry * l.jacobian;
    return mode == yarf::TransportMode::kImportance ? f * l.eta * l.eta : f;
  }

  // int_ior / ext_ior: the index below the surface over the one above.
  float eta_;
  mf::TexturedRoughness roughness_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<RoughDielectric>(
      registrar, "roughdielectric", "1.0.0",
      "Rough dielectric interface: GGX microfacet reflection and refraction (Walter 2007)");
}
