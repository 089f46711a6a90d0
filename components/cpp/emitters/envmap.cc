// envmap — an environment map: radiance arriving from every direction, read
// from an image (Mitsuba's `envmap`, pbrt-v4's image `infinite` light)
//
// The kernel asks for the light's local direction of travel w (a Light of
// kind ENVIRONMENT, placed by to_world); the image is looked up toward
// -w, where the light comes from.
//
// Parameters: EnvironmentMap::Parameters() below.
// The image is any OpenImageIO reads: float images (EXR, HDR, PFM) are
// linear, integer ones are decoded from sRGB. The mappings:
//   "latlong" (Mitsuba): u = atan2(d.x, −d.z) / 2π, v = acos(d.y) / π,
//   +y up; looked up bilinearly as Mitsuba 3 does: texel (x, y) of a
//   W × H image sits at u = (x + ½) / W, v = y / (H − 1), so the first
//   row is the zenith and the last the nadir, and u wraps around.
//   "equal_area" (pbrt-v4): Clarberg's equal-area octahedral map of
//   the sphere onto a square image, +z up, looked up at the nearest
//   texel as pbrt-v4 does.
//
// Directions are sampled from a piecewise-constant distribution over the
// image's cells (sin θ-weighted for latlong, whose cells are not of equal
// solid angle; its cells are shifted half a texel in u, to span the
// interval between two columns). A cell's weight is the largest
// luminance among the texels its radiance interpolates, so the density
// is positive wherever the radiance is.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "../textures/linear_image.h"
#include "piecewise_constant.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Error;
using yarf::Vec3;
using yarf::kPi;

class EnvironmentMap final : public yarf::Emitter {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    yarf::ParameterSchema schema =
        yarf::textures::ImageFileParameters("the environment image; it or asset is required");
    schema.insert(schema.end(), {
        P::Float("scale").Default(1).Min(0).Doc("multiplies the radiance"),
        P::String("mapping").Default("latlong").Choices({"latlong", "equal_area"}).Doc(
            "how the image covers the sphere: latlong (Mitsuba) or equal_area (pbrt-v4)"),
    });
    return schema;
  }

  explicit EnvironmentMap(const yarf::Properties& props) {
    const std::string mapping = props.String("mapping", "latlong");
    if (mapping != "latlong" && mapping != "equal_area")
      throw Error("property 'mapping' must be \"latlong\" or \"equal_area\", not \"" + mapping + "\"");
    equal_area_ = mapping == "equal_area";
    scale_ = float(props.Float("scale", 1.0));
    if (!(scale_ >= 0) || !std::isfinite(scale_)) throw Error("property 'scale' must be finite and >= 0");
    image_ = yarf::textures::ReadLinearImage(props.ResolvedFile("filename"), {}, "filename");
    if (equal_area_ && image_.width != image_.height)
      throw Error("property 'filename': an equal-area map is square, not " + std::to_string(image_.width) + " x " +
                  std::to_string(image_.height));
    for (float& value : image_.texels)
      if (!(value >= 0) || !std::isfinite(value)) value = 0;  // NaN, ∞ and negative texels emit nothing
    BuildDistribution();
  }

  void Radiance(std::span<const float> w, const yarf::SurfacePoints&, std::span<float> radiance) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k) (Lookup(-Vec3::Load(&w[3 * k])) * scale_).Store(&radiance[3 * k]);
  }

  void SampleDirection(std::span<const float> uniform, std::span<float> w, std::span<float> pdf) const override {
    const size_t count = uniform.size() / 2;
    for (size_t k = 0; k < count; ++k) {
      float cell_pdf = 0;
      const auto [cell_u, v] = cells_.Sample(uniform[2 * k], uniform[2 * k + 1], cell_pdf);
      const Vec3 toward = Direction(FromCells(cell_u), v);
      (-toward).Store(&w[3 * k]);
      pdf[k] = DirectionPdf(cell_pdf, toward);
    }
  }

  void PdfDirection(std::span<const float> w, std::span<float> pdf) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k) {
      const Vec3 toward = -Vec3::Load(&w[3 * k]);
      const auto [u, v] = ImageUv(toward);
      pdf[k] = DirectionPdf(cells_.Pdf(ToCells(u), v), toward);
    }
  }

 private:
  // Image coordinates in [0, 1]² of a unit direction toward the light.
  std::array<float, 2> ImageUv(Vec3 d) const {
    if (equal_area_) return yarf::EqualAreaSphereToSquare(d);
    float u = std::atan2(d.x, -d.z) / (2 * kPi);
    u -= std::floor(u);
    return {u, std::acos(std::clamp(d.y, -1.0f, 1.0f)) / kPi};
  }

  // The cells' u from the image's and back: latlong cells start at the
  // first texel column's centre.
  float CellShift() const { return equal_area_ ? 0.0f : 0.5f / float(image_.width); }
  float ToCells(float u) const {
    const float shifted = u - CellShift();
    return shifted - std::floor(shifted);
  }
  float FromCells(float u) const {
    const float shifted = u + CellShift();
    return shifted - std::floor(shifted);
  }

  Vec3 Direction(float u, float v) const {
    if (equal_area_) return yarf::EqualAreaSquareToSphere(u, v);
    const float phi = 2 * kPi * u, theta = kPi * v;
    const float sin_theta = std::sin(theta);
    return {sin_theta * std::sin(phi), std::cos(theta), -sin_theta * std::cos(phi)};
  }

  // Solid-angle density from a density over the image square.
  float DirectionPdf(float image_pdf, Vec3 d) const {
    if (equal_area_) return image_pdf / (4 * kPi);
    const float sin_theta = std::sqrt(std::max(0.0f, 1 - d.y * d.y));
    return sin_theta > 0 ? image_pdf / (2 * kPi * kPi * sin_theta) : 0.0f;
  }

  Vec3 Texel(int x, int y) const {
    const float* t = &image_.texels[(size_t(y) * size_t(image_.width) + size_t(x)) * size_t(image_.channels)];
    return image_.channels == 3 ? Vec3(t[0], t[1], t[2]) : Vec3(t[0], t[0], t[0]);
  }

  // Continuous texel coordinates of latlong uv: texel (x, y) sits at (x, y).
  std::array<float, 2> TexelPosition(float u, float v) const {
    return {u * float(image_.width) - 0.5f, v * float(image_.height - 1)};
  }

  Vec3 Lookup(Vec3 d) const {
    const auto [u, v] = ImageUv(d);
    if (equal_area_) {
      const int x = std::clamp(int(u * float(image_.width)), 0, image_.width - 1);
      const int y = std::clamp(int(v * float(image_.height)), 0, image_.height - 1);
      return Texel(x, y);
    }
    const auto [px, py] = TexelPosition(u, v);
    const int x0 = (int(std::floor(px)) + image_.width) % image_.width;
    const int y0 = std::clamp(int(py), 0, std::max(0, image_.height - 2));
    const int x1 = (x0 + 1) % image_.width, y1 = std::min(y0 + 1, image_.height - 1);
    const float fx = std::clamp(px - std::floor(px), 0.0f, 1.0f), fy = std::clamp(py - float(y0), 0.0f, 1.0f);
    return (Texel(x0, y0) * (1 - fx) + Texel(x1, y0) * fx) * (1 - fy) +
           (Texel(x0, y1) * (1 - fx) + Texel(x1, y1) * fx) * fy;
  }

  // One cell per texel over the image square.
  void BuildDistribution() {
    const int width = image_.width, height = image_.height;
    std::vector<float> weights(size_t(width) * size_t(height));
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        float weight = 0;
        if (equal_area_) {
          weight = yarf::Luminance(Texel(x, y));
        } else {
          // The texels the bilinear lookup reads inside this cell:
          // columns x and x + 1, the rows its v interval spans.
          const float v0 = float(y) / float(height), v1 = float(y + 1) / float(height);
          const int first = int(std::floor(TexelPosition(0, v0)[1]));
          const int last = std::min(height - 1, int(std::ceil(TexelPosition(0, v1)[1])));
          for (int row = first; row <= last; ++row)
            for (int column : {x, (x + 1) % width}) weight = std::max(weight, yarf::Luminance(Texel(column, row)));
          weight *= std::sin(kPi * (float(y) + 0.5f) / float(height));
        }
        weights[size_t(y) * size_t(width) + size_t(x)] = weight;
      }
    }
    cells_ = yarf::PiecewiseConstant2D(std::move(weights), width, height);
  }

  bool equal_area_ = false;
  float scale_ = 1;
  yarf::textures::LinearImage image_;
  yarf::PiecewiseConstant2D cells_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<EnvironmentMap>(registrar, "envmap", "1.0.0",
                                 "Environment map: radiance from every direction, read from an image");
}
