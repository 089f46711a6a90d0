// The 2-D affine map from a surface's uv to where a texture is looked up
// (bitmap.cc, checkerboard.cc), read from Mitsuba's `to_uv` or pbrt's
// uscale / vscale / udelta / vdelta.
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "yarf/error.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/vecmath.h"

namespace yarf::textures {

// (u', v') = (a u + b v + c, d u + e v + f), held as {a, b, c, d, e, f}.
struct UvMap {
  std::array<double, 6> m{1, 0, 0, 0, 1, 0};

  double U(double u, double v) const { return m[0] * u + m[1] * v + m[2]; }
  double V(double u, double v) const { return m[3] * u + m[4] * v + m[5]; }
  // A footprint (du/dx, dv/dx, du/dy, dv/dy) moves with the linear part.
  std::array<double, 4> Footprint(const std::array<float, 4>& d) const {
    return {m[0] * d[0] + m[1] * d[1], m[3] * d[0] + m[4] * d[1], m[0] * d[2] + m[1] * d[3],
            m[3] * d[2] + m[4] * d[3]};
  }
  // Scales u' and v' alike (checkerboard's cells per unit).
  UvMap Scaled(double s) const {
    UvMap out = *this;
    for (double& x : out.m) x *= s;
    return out;
  }
  // No rotation or shear: u' depends on u alone, v' on v alone.
  bool Separable() const { return m[1] == 0 && m[3] == 0; }
};

inline double RequireFinite(double x, const std::string& key) {
  if (!std::isfinite(x)) throw Error("property '" + key + "' must be a finite number");
  return x;
}

// The parameters ReadUvMap reads. None has a declared default: a key
// given chooses Mitsuba's form or pbrt's.
inline std::vector<Parameter> UvMapParameters() {
  return {
      Parameter::Matrix("to_uv").Doc("Mitsuba's uv map: its action on (u, v, 0); identity when absent"),
      Parameter::Float("uscale").Doc("pbrt's u' = u·uscale + udelta (1 when absent)"),
      Parameter::Float("vscale").Doc("pbrt's v' = v·vscale + vdelta (1 when absent)"),
      Parameter::Float("udelta").Doc("pbrt's offset of u' (0 when absent)"),
      Parameter::Float("vdelta").Doc("pbrt's offset of v' (0 when absent)"),
      Parameter::String("mapping").Choices({"uv"}).Doc("pbrt's; uv, the only one (others need surface positions)"),
  };
}

// Mitsuba's to_uv is a 4×4 transform of which the map is its action on
// the point (u, v, 0) (Mitsuba's Transform4f::extract keeps the upper-left
// 2×2 and the translation column); pbrt's is u' = u·uscale + udelta,
// v' = v·vscale + vdelta. One scene gives one form or the other. pbrt's
// `mapping` may be given, as "uv": the other mappings (spherical,
// cylindrical, planar) need the surface position, which a lookup lacks.
inline UvMap ReadUvMap(const Properties& props) {
  const std::string mapping = props.String("mapping", "uv");
  if (mapping != "uv")
    throw Error("property 'mapping': only \"uv\" is supported (textures are looked up by uv alone); got '" +
                mapping + "'");
  const bool pbrt = props.Has("uscale") || props.Has("vscale") || props.Has("udelta") || props.Has("vdelta");
  UvMap map;
  if (props.Has("to_uv")) {
    if (pbrt) throw Error("property 'to_uv' cannot be combined with uscale / vscale / udelta / vdelta");
    const Transform t = props.Matrix("to_uv", Transform::Identity());
    for (double x : t.m) RequireFinite(x, "to_uv");
    map.m = {t.m[0], t.m[1], t.m[3], t.m[4], t.m[5], t.m[7]};
    return map;
  }
  map.m = {RequireFinite(props.Float("uscale", 1.0), "uscale"), 0, RequireFinite(props.Float("udelta", 0.0), "udelta"),
           0, RequireFinite(props.Float("vscale", 1.0), "vscale"), RequireFinite(props.Float("vdelta", 0.0), "vdelta")};
  return map;
}

}  // namespace yarf::textures
