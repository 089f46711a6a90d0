// checkerboard — two colours in alternating square cells (Mitsuba's and
// pbrt-v4's `checkerboard`)
//
// Parameters: Checkerboard::Parameters() below, in two forms. The keys
// given choose the form (none: Mitsuba's); keys of both forms in one
// texture are an error, so none has a declared default.
//   Mitsuba's (color0, color1, to_uv): 2 × 2 cells over the unit square
//   of the mapped uv (u', v'): color0 where frac(u') and frac(v') lie on
//   the same side of ½ (both ≤ ½ or both > ½), color1 elsewhere, as
//   Mitsuba 3's eval.
//   pbrt-v4's (tex1, tex2, uscale, vscale, udelta, vdelta, mapping):
//   cells of side 1 in (s, t) = (u·uscale + udelta, v·vscale + vdelta):
//   tex1 where ⌊s⌋ + ⌊t⌋ is even, tex2 where it is odd. With the default
//   scales the whole unit square is one tex1 cell, as in pbrt. pbrt's
//   3-D checkerboard (`dimension` 3) is not offered.
//
// Filtering: a point lookup (no footprint) gives the exact cell colour.
// With a footprint, the value is the average of the pattern over a box
// around the point, in closed form (pbrt-v3's CheckerboardTexture): the
// box's half-widths are max(|ds/dx|, |ds/dy|) and max(|dt/dx|, |dt/dy|)
// in cell units, and because the pattern is the product of two square
// waves its box average is the product of two 1-D averages. A distant
// checkerboard thus converges to the mean colour instead of aliasing.
// Textured colours are evaluated at the point and blended by that weight.
//
// Channels: 3. Mean: the blend of the colours' means by the fraction of
// the unit square in second-colour cells (exact for maps without rotation
// or shear, by a 1024² grid otherwise; textured colours are assumed
// independent of the pattern).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <vector>

#include "texture_input.h"
#include "texture_rows.h"
#include "uv_map.h"
#include "yarf/plugin.h"

namespace {

using yarf::Vec3;
using yarf::textures::TextureInput;

enum class Form { kMitsuba, kPbrt };

// Whether checker coordinate x (cells of side 1) lies in an odd cell.
bool OddCell(double x, Form form) {
  // Mitsuba tests frac(u') > ½ with x = 2u', which puts a cell's upper
  // edge in the cell below; pbrt takes ⌊x⌋, which puts it in the cell above.
  if (form == Form::kMitsuba) return x / 2 - std::floor(x / 2) > 0.5;
  return std::fmod(std::floor(x), 2.0) != 0.0;
}

// ∫₀ˣ of the odd cells' indicator: one per two cells, plus the part of
// the odd cell x lies in.
double OddIntegral(double x) {
  const double pairs = std::floor(x / 2);
  return pairs + std::max(0.0, x - 2 * pairs - 1);
}

// The fraction of [x − r, x + r] in odd cells.
double OddFraction(double x, double r, Form form) {
  double lo = x - r, hi = x + r;
  if (std::floor(lo) == std::floor(hi)) return OddCell(x, form) ? 1.0 : 0.0;
  // Shifted by an even number of cells (which changes nothing) so that
  // far from the origin the difference keeps its digits.
  const double shift = 2 * std::floor(lo / 2);
  lo -= shift;
  hi -= shift;
  return std::clamp((OddIntegral(hi) - OddIntegral(lo)) / (hi - lo), 0.0, 1.0);
}

// The weight of the second colour when the two axes' odd fractions are
// ps and pt: a cell is second-colour when exactly one axis is odd.
double SecondWeight(double ps, double pt) { return ps * (1 - pt) + pt * (1 - ps); }

bool HasAny(const yarf::Properties& props, std::initializer_list<const char*> keys) {
  return std::any_of(keys.begin(), keys.end(), [&](const char* key) { return props.Has(key); });
}

Form ReadForm(const yarf::Properties& props) {
  const bool pbrt = HasAny(props, {"tex1", "tex2", "uscale", "vscale", "udelta", "vdelta", "mapping"});
  if (pbrt && HasAny(props, {"color0", "color1", "to_uv"}))
    throw yarf::Error(
        "checkerboard takes Mitsuba's properties (color0, color1, to_uv) or pbrt's (tex1, tex2, "
        "uscale, vscale, udelta, vdelta), not both");
  return pbrt ? Form::kPbrt : Form::kMitsuba;
}

class Checkerboard final : public yarf::Texture {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    yarf::ParameterSchema schema = {
        P::RgbTexture("color0").Doc("Mitsuba's first colour (0.4 when absent)"),
        P::RgbTexture("color1").Doc("Mitsuba's second colour (0.2 when absent)"),
        P::RgbTexture("tex1").Doc("pbrt's colour of even cells (1 when absent)"),
        P::RgbTexture("tex2").Doc("pbrt's colour of odd cells (0 when absent)"),
    };
    const yarf::ParameterSchema map = yarf::textures::UvMapParameters();
    schema.insert(schema.end(), map.begin(), map.end());
    return schema;
  }

  explicit Checkerboard(const yarf::Properties& props)
      : form_(ReadForm(props)),
        first_(form_ == Form::kPbrt ? TextureInput::Color(props, "tex1", Vec3(1, 1, 1))
                                    : TextureInput::Color(props, "color0", Vec3(0.4f, 0.4f, 0.4f))),
        second_(form_ == Form::kPbrt ? TextureInput::Color(props, "tex2", Vec3(0, 0, 0))
                                     : TextureInput::Color(props, "color1", Vec3(0.2f, 0.2f, 0.2f))),
        // Mitsuba's cells are half a unit of uv: cell units are 2u'.
        map_(yarf::textures::ReadUvMap(props).Scaled(form_ == Form::kMitsuba ? 2.0 : 1.0)) {}

  uint32_t Channels() const override { return 3; }

  void Evaluate(const yarf::SurfacePoints& at, std::span<float> value) const override {
    yarf::textures::Blend(at, value, first_, second_, [&](size_t k) {
      const double u = at.uv[2 * k], v = at.uv[2 * k + 1];
      const std::array<double, 4> d = map_.Footprint(yarf::textures::FootprintAt(at, k));
      const double rs = std::max(std::abs(d[0]), std::abs(d[2]));
      const double rt = std::max(std::abs(d[1]), std::abs(d[3]));
      return float(SecondWeight(OddFraction(map_.U(u, v), rs, form_), OddFraction(map_.V(u, v), rt, form_)));
    });
  }

  std::vector<float> Mean() const override {
    const float f = float(SecondFraction());
    const Vec3 mean = (1.0f - f) * first_.Mean() + f * second_.Mean();
    return {mean.x, mean.y, mean.z};
  }

 private:
  // The fraction of the unit square of uv in second-colour cells.
  double SecondFraction() const {
    if (map_.Separable()) {
      // The unit square maps to the box centred at the image of (½, ½).
      const double ps = OddFraction(map_.U(0.5, 0.5), std::abs(map_.m[0]) / 2, form_);
      const double pt = OddFraction(map_.V(0.5, 0.5), std::abs(map_.m[4]) / 2, form_);
      return SecondWeight(ps, pt);
    }
    constexpr int kGrid = 1024;
    int64_t second = 0;
    for (int i = 0; i < kGrid; ++i)
      for (int j = 0; j < kGrid; ++j) {
        const double u = (i + 0.5) / kGrid, v = (j + 0.5) / kGrid;
        second += OddCell(map_.U(u, v), form_) != OddCell(map_.V(u, v), form_);
      }
    return double(second) / (double(kGrid) * kGrid);
  }

  Form form_;
  TextureInput first_, second_;
  yarf::textures::UvMap map_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Checkerboard>(registrar, "checkerboard", "1.0.0",
                               "Two colours in alternating cells, box-filtered in closed form (Mitsuba / pbrt-v4)");
}
