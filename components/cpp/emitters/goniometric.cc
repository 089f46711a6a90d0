// goniometric — a point light whose intensity varies with direction as an
// image over the sphere says (pbrt-v4's GoniometricLight)
//
// The image is a square map of the sphere in Clarberg's equal-area
// octahedral mapping (warps.h: EqualAreaSquareToSphere), +z of the
// light's frame at its centre; each texel stands for the same solid angle.
// Toward a light-space direction l the intensity is
//     I(l) = scale · intensity · g(EqualAreaSphereToSquare(l)),
// g the texel nearest to that point (pbrt-v4's lookup), an RGB texel's
// mean (not its luminance: pbrt-v4 averages the channels). The power is
// 4π · scale · intensity · (mean of g).
//
// The light's frame is to_world's linear part M, which may have a roll and
// even a mirror (pbrt-v4 swaps y and z; the importer says so in to_world):
// the kernel hands directions in the frame of the axis alone
// (light_frame.h). Directions are sampled texel by texel in proportion to
// g; a direction's world density is 1 / 4π times the texel's share times
// |M·l|³ / |det M|.
//
// Parameters: Goniometric::Parameters() below. Integer images are decoded
// from sRGB.
#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include "../textures/linear_image.h"
#include "intensity.h"
#include "light_frame.h"
#include "piecewise_constant.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Error;
using yarf::Vec3;
using yarf::kPi;

class Goniometric final : public yarf::Emitter {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    yarf::ParameterSchema schema =
        yarf::textures::ImageFileParameters("the square equal-area image g; it or asset is required");
    schema.insert(schema.end(), {
        yarf::IntensityParameter("intensity", "intensity where g is 1, W·sr⁻¹").Default(1.0),
        P::Float("scale").Default(1).Min(0).Doc("multiplies the intensity"),
        yarf::LightToWorldParameter(),
    });
    return schema;
  }

  explicit Goniometric(const yarf::Properties& props)
      : frame_(props.Matrix("to_world", yarf::Transform::Identity())) {
    const float scale = float(props.Float("scale", 1.0));
    if (!(scale >= 0) || !std::isfinite(scale)) throw Error("property 'scale' must be finite and >= 0");
    intensity_ = (props.Has("intensity") ? yarf::RequiredIntensity(props, "intensity") : Vec3(1, 1, 1)) * scale;
    if (!props.Has("filename")) throw Error("property 'filename' (the equal-area image) is missing");
    const auto image = yarf::textures::ReadLinearImage(props.ResolvedFile("filename"), {}, "filename");
    if (image.width != image.height)
      throw Error("property 'filename': the image must be square (an equal-area map), not " +
                  std::to_string(image.width) + " x " + std::to_string(image.height));
    side_ = image.width;
    grey_.resize(size_t(side_) * size_t(side_));
    for (size_t i = 0; i < grey_.size(); ++i) {
      const float* t = &image.texels[i * size_t(image.channels)];
      const float g = image.channels == 3 ? (t[0] + t[1] + t[2]) / 3 : t[0];
      grey_[i] = g >= 0 && std::isfinite(g) ? g : 0.0f;  // negative texels emit nothing
    }
    if (std::all_of(grey_.begin(), grey_.end(), [](float g) { return g == 0; })) {
      cells_ = yarf::PiecewiseConstant2D(std::vector<float>(grey_.size(), 1.0f), side_, side_);
    } else {
      cells_ = yarf::PiecewiseConstant2D(grey_, side_, side_);
    }
  }

  void Radiance(std::span<const float> w, const yarf::SurfacePoints&, std::span<float> radiance) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k) {
      const Vec3 l = yarf::Normalize(frame_.FromKernel(Vec3::Load(&w[3 * k])));
      const auto [u, v] = yarf::EqualAreaSphereToSquare(l);
      (intensity_ * Grey(u, v)).Store(&radiance[3 * k]);
    }
  }

  void SampleDirection(std::span<const float> uniform, std::span<float> w, std::span<float> pdf) const override {
    const size_t count = uniform.size() / 2;
    for (size_t k = 0; k < count; ++k) {
      float square_pdf = 0;
      const auto [u, v] = cells_.Sample(uniform[2 * k], uniform[2 * k + 1], square_pdf);
      const Vec3 l = yarf::EqualAreaSquareToSphere(u, v);
      frame_.ToKernel(l).Store(&w[3 * k]);
      pdf[k] = square_pdf / (4 * kPi) * frame_.DensityFactor(l);
    }
  }

  void PdfDirection(std::span<const float> w, std::span<float> pdf) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k) {
      const Vec3 l = yarf::Normalize(frame_.FromKernel(Vec3::Load(&w[3 * k])));
      const auto [u, v] = yarf::EqualAreaSphereToSquare(l);
      pdf[k] = cells_.Pdf(u, v) / (4 * kPi) * frame_.DensityFactor(l);
    }
  }

 private:
  float Grey(float u, float v) const {
    const int x = std::clamp(int(u * float(side_)), 0, side_ - 1), y = std::clamp(int(v * float(side_)), 0, side_ - 1);
    return grey_[size_t(y) * size_t(side_) + size_t(x)];
  }

  yarf::LightFrame frame_;
  Vec3 intensity_;
  int side_ = 0;
  std::vector<float> grey_;  // row by row from v = 0
  yarf::PiecewiseConstant2D cells_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Goniometric>(registrar, "goniometric", "1.0.0",
                              "Point light whose intensity over directions is an equal-area image (pbrt-v4)");
}
