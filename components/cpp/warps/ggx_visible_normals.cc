// ggx_visible_normals — GGX microfacet normals visible from a direction
//
// Samples the normals m of an anisotropic GGX (Trowbridge–Reitz)
// microsurface in proportion to the area they show to the view direction
// wi: the distribution of visible normals
//   D_wi(m) = G1(wi) · max(0, wi·m) · D(m) / wi.z
// with the GGX D and Smith's G1, by Heitz's method ("Sampling the GGX
// Distribution of Visible Normals", JCGT 2018). A microfacet BSDF that
// draws m this way and reflects wi about it never wastes a sample on a
// normal facing away from wi or hidden behind other microfacets.
//
// Signature: [0,1)² → unit normals m (z ≥ 0), pdf D_wi(m) per steradian of
// m; 0 where wi·m ≤ 0, for z ≤ 0 and for points that are not unit vectors.
// Inverse: none.
//
// Parameters: GgxVisibleNormals::Parameters() below. wi is normalised
// here and must point above the surface (z > 0).
#include <cmath>
#include <string>

#include "square_warp.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

// Below this the lobe is a mirror whose peak density 1/(π α²) loses
// meaning in float.
constexpr double kMinAlpha = 1e-4;

float RequireAlpha(const std::string& key, double alpha) {
  if (!(alpha >= kMinAlpha && std::isfinite(alpha)))
    throw yarf::Error("property '" + key + "' must be a finite number ≥ 1e-4 (got " +
                      std::to_string(alpha) + ")");
  return float(alpha);
}

Vec3 RequireDirectionAbove(Vec3 wi) {
  const float length = yarf::Length(wi);
  if (!(std::isfinite(length) && length > 0))
    throw yarf::Error("property 'wi' must be a nonzero, finite direction");
  const Vec3 w = wi / length;
  if (!(w.z > 0)) throw yarf::Error("property 'wi' must point above the surface (z > 0)");
  return w;
}

class GgxVisibleNormals {
 public:
  static const char* Name() { return "ggx_visible_normals"; }

  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::Float("alpha_x").Default(0.1).Min(kMinAlpha).Doc("roughness along x (GGX α, the slope's scale)"),
        P::Float("alpha_y").Min(kMinAlpha).Doc("roughness along y; alpha_x when not given"),
        P::Vector("wi").Default(Vec3(0.0f, 0.0f, 1.0f)).Doc("the view direction, above the surface (z > 0)"),
    };
  }

  explicit GgxVisibleNormals(const yarf::Properties& props)
      : alpha_x_(RequireAlpha("alpha_x", props.Float("alpha_x", 0.1))),
        alpha_y_(RequireAlpha("alpha_y", props.Float("alpha_y", alpha_x_))),
        wi_(RequireDirectionAbove(props.Vector("wi", Vec3(0.0f, 0.0f, 1.0f)))) {}

  Vec3 Sample(float u0, float u1) const {
    return yarf::SampleGgxVisibleNormal(wi_, alpha_x_, alpha_y_, u0, u1);
  }
  float Density(Vec3 m) const { return yarf::GgxVisibleNormalPdf(wi_, m, alpha_x_, alpha_y_); }

 private:
  float alpha_x_, alpha_y_;
  Vec3 wi_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::DirectionWarp<GgxVisibleNormals>>(
      registrar, "ggx_visible_normals", "1.0.0",
      "GGX microfacet normals visible from a direction (Heitz 2018), anisotropic");
}
