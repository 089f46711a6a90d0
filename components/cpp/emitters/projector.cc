// projector — a point light projecting an image through a perspective
// frustum (Mitsuba 3's `projector`, the reciprocal of its perspective
// camera)
//
// The image is the irradiance on the virtual image plane z = 1 in front of
// the light (times π, as Mitsuba 3 has it): the intensity toward a
// direction making the angle θ with the axis is
//     I = π · scale · E(u, v) / cos³θ,
// so that a plane facing the projector at unit distance receives π·scale·E
// everywhere, undistorted. (Mitsuba's sample_direction divides by
// z² · cos θ, the same for a rigid to_world; the general form below is
// its formula for any linear part of to_world.) Radiance is 0 outside the
// frustum and behind the light.
//
// Mitsuba's camera space: +z forward, +x left, +y up. A camera-space point
// q (q.z > 0) is seen at u = ½ − ½·q.x / (q.z·tan(fov_x/2)) and
// v = ½ − ½·q.y / (q.z·tan(fov_y/2)), tan(fov_y/2) = tan(fov_x/2)·H/W:
// u = 0 is the image's left column seen from behind the projector, v = 0
// its top row. The image is looked up as Mitsuba's bitmap texture does:
// bilinear between the texels around u·W − ½, v·H − ½, the texels beyond
// the border taken by the wrap mode (Mitsuba's default "repeat" wraps
// around, so the half texel along each border blends with the opposite
// side), or the nearest texel.
//
// The kernel gives a point light's directions in the frame Frame(axis) it
// builds from the axis alone (the image of +z by to_world; see
// KernelScene::AddLight), which loses the light's roll; the projector
// therefore takes to_world too and rebuilds that frame to find its own x
// and y.
//
// Directions are sampled over the image plane by a piecewise-constant
// density over half-texel cells, each weighted by the largest luminance of
// the (at most four) texels its lookups read, so that every sampled
// direction receives light; the solid-angle density is the plane's
// density times |M·q|³ / |det M| (q on the plane, M to_world's linear
// part), 1 / (A·cos³θ)-shaped for a uniform image.
//
// Parameters: Projector::Parameters() below. The image is any
// OpenImageIO reads; integer images are decoded from sRGB unless raw.
// With image "intensity" the image is the intensity itself,
// I = scale · E(u, v) in W·sr⁻¹ with no π and no 1/cos³θ (pbrt-v4's
// ProjectionLight; for a non-rigid to_world, the intensity in the light's
// own space).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "../textures/linear_image.h"
#include "intensity.h"
#include "light_frame.h"
#include "piecewise_constant.h"
#include "yarf/plugin.h"

namespace {

using yarf::Error;
using yarf::Vec3;
using yarf::kPi;

using yarf::Matrix3;

double Radians(double degrees) { return degrees * 3.14159265358979323846 / 180.0; }

// Half the width of the image plane at z = 1 for a field of view `fov`
// (degrees) along `axis` of an image of aspect W / H (Mitsuba's parse_fov).
double TanHalfFovX(double fov, const std::string& axis, double aspect) {
  const double t = std::tan(Radians(fov) / 2);
  if (axis == "x") return t;
  if (axis == "y") return t * aspect;
  if (axis == "diagonal") return t / std::sqrt(1 + 1 / (aspect * aspect));
  if (axis == "smaller") return aspect > 1 ? t * aspect : t;
  if (axis == "larger") return aspect < 1 ? t * aspect : t;
  throw Error("property 'fov_axis' must be \"x\", \"y\", \"diagonal\", \"smaller\" or \"larger\", not \"" + axis +
              "\"");
}

class Projector final : public yarf::Emitter {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    yarf::ParameterSchema schema =
        yarf::textures::ImageFileParameters("the projected image; it (or asset) or irradiance is required");
    schema.insert(schema.end(), {
        yarf::IntensityParameter("irradiance", "a constant image (1 × 1) in place of a file"),
        P::Bool("raw").Default(false).Doc("takes an integer image's values as they are, not as sRGB"),
        P::String("filter_type").Default("bilinear").Choices({"bilinear", "nearest"}).Doc("the image's lookup"),
        P::String("wrap_mode").Default("repeat").Choices({"repeat", "mirror", "clamp"}).Doc(
            "the texels beyond the image's border"),
        P::Float("scale").Default(1).Min(0).Doc("multiplies the image"),
        P::Float("fov").Required().Range(0, 180).Doc("field of view in degrees, along fov_axis"),
        P::String("fov_axis").Default("x").Choices({"x", "y", "diagonal", "smaller", "larger"}).Doc(
            "the image's extent fov spans"),
        yarf::LightToWorldParameter(),
        P::String("image").Default("irradiance").Choices({"irradiance", "intensity"}).Doc(
            "what the image is: irradiance on the plane z = 1 (Mitsuba) or intensity (pbrt-v4)"),
    });
    return schema;
  }

  explicit Projector(const yarf::Properties& props) {
    scale_ = float(props.Float("scale", 1.0));
    if (!(scale_ >= 0) || !std::isfinite(scale_)) throw Error("property 'scale' must be finite and >= 0");
    const std::string filter = props.String("filter_type", "bilinear");
    if (filter != "bilinear" && filter != "nearest")
      throw Error("property 'filter_type' must be \"bilinear\" or \"nearest\", not \"" + filter + "\"");
    bilinear_ = filter == "bilinear";
    const std::string wrap = props.String("wrap_mode", "repeat");
    if (wrap == "repeat") {
      wrap_ = Wrap::kRepeat;
    } else if (wrap == "mirror") {
      wrap_ = Wrap::kMirror;
    } else if (wrap == "clamp") {
      wrap_ = Wrap::kClamp;
    } else {
      throw Error("property 'wrap_mode' must be \"repeat\", \"mirror\" or \"clamp\", not \"" + wrap + "\"");
    }
    const bool raw = props.Bool("raw", false);
    if (props.Has("filename") == props.Has("irradiance"))
      throw Error("give the projected image as 'filename' or a constant 'irradiance', one of them");
    if (props.Has("filename")) {
      yarf::textures::Encoding encoding;
      if (raw) encoding.kind = yarf::textures::Encoding::Kind::kLinear;
      image_ = yarf::textures::ReadLinearImage(props.ResolvedFile("filename"), encoding, "filename");
      for (float& value : image_.texels)
        if (!(value >= 0) || !std::isfinite(value)) value = 0;  // negative texels project nothing
    } else {
      const Vec3 constant = yarf::RequiredIntensity(props, "irradiance");
      image_.width = image_.height = 1;
      image_.channels = 3;
      image_.texels = {constant.x, constant.y, constant.z};
    }

    const std::string image_is = props.String("image", "irradiance");
    if (image_is != "irradiance" && image_is != "intensity")
      throw Error("property 'image' must be \"irradiance\" or \"intensity\", not \"" + image_is + "\"");
    intensity_image_ = image_is == "intensity";
    if (!props.Has("fov")) throw Error("property 'fov' (degrees) is missing");
    const double fov = props.Float("fov");
    if (!(fov > 0 && fov < 180)) throw Error("property 'fov' must lie in (0, 180) degrees");
    const double aspect = double(image_.width) / double(image_.height);
    const double tan_x = TanHalfFovX(fov, props.String("fov_axis", "x"), aspect);
    if (!(tan_x > 0) || !std::isfinite(tan_x) || !(tan_x / aspect > 0))
      throw Error("property 'fov' gives a degenerate frustum for this image");
    tan_x_ = float(tan_x);
    tan_y_ = float(tan_x / aspect);
    plane_area_ = float(4 * tan_x * (tan_x / aspect));

    const yarf::Transform to_world = props.Matrix("to_world", yarf::Transform::Identity());
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) linear_.m[size_t(3 * i + j)] = to_world.m[size_t(4 * i + j)];
    const double det = linear_.Determinant();
    if (!(std::abs(det) > 1e-12) || !std::isfinite(det))
      throw Error("property 'to_world' must be an invertible transform");
    abs_det_ = float(std::abs(det));
    inverse_ = linear_.Inverse();
    // The frame the kernel hands directions in (as KernelScene::AddLight).
    kernel_frame_ = yarf::Frame(yarf::Normalize(to_world.Vector(Vec3(0, 0, 1))));
    forward_ = linear_ * Vec3(0, 0, 1);
    BuildDistribution();
  }

  void Radiance(std::span<const float> w, const yarf::SurfacePoints&, std::span<float> radiance) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k) {
      const Vec3 d = kernel_frame_.ToWorld(Vec3::Load(&w[3 * k]));
      const Vec3 c = inverse_ * d;  // camera space
      float u = 0, v = 0;
      Vec3 value;
      const float cos_forward = yarf::Dot(forward_, d);
      if (ImageUv(c, u, v) && cos_forward > 0)
        value = intensity_image_ ? Lookup(u, v) * scale_ : Lookup(u, v) * (kPi * scale_ / (c.z * c.z * cos_forward));
      value.Store(&radiance[3 * k]);
    }
  }

  void SampleDirection(std::span<const float> uniform, std::span<float> w, std::span<float> pdf) const override {
    const size_t count = uniform.size() / 2;
    for (size_t k = 0; k < count; ++k) {
      float image_pdf = 0;
      const auto [u, v] = cells_.Sample(uniform[2 * k], uniform[2 * k + 1], image_pdf);
      const Vec3 q((1 - 2 * u) * tan_x_, (1 - 2 * v) * tan_y_, 1);
      const Vec3 toward = linear_ * q;
      kernel_frame_.ToLocal(yarf::Normalize(toward)).Store(&w[3 * k]);
      pdf[k] = DirectionPdf(image_pdf, toward);
    }
  }

  void PdfDirection(std::span<const float> w, std::span<float> pdf) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k) {
      const Vec3 d = kernel_frame_.ToWorld(Vec3::Load(&w[3 * k]));
      const Vec3 c = inverse_ * d;
      float u = 0, v = 0;
      pdf[k] = ImageUv(c, u, v) ? DirectionPdf(cells_.Pdf(u, v), linear_ * (c / c.z)) : 0.0f;
    }
  }

 private:
  enum class Wrap { kRepeat, kMirror, kClamp };

  // The image coordinates camera-space direction c meets the plane z = 1
  // at; false behind the light or outside the frustum.
  bool ImageUv(Vec3 c, float& u, float& v) const {
    if (!(c.z > 0)) return false;
    u = 0.5f - 0.5f * c.x / (c.z * tan_x_);
    v = 0.5f - 0.5f * c.y / (c.z * tan_y_);
    return u >= 0 && u <= 1 && v >= 0 && v <= 1;
  }

  // World solid-angle density of the direction toward M·q (q on the plane
  // z = 1) from a density over the image square.
  float DirectionPdf(float image_pdf, Vec3 toward) const {
    const float length = yarf::Length(toward);
    return image_pdf * length * length * length / (plane_area_ * abs_det_);
  }

  // Mitsuba's wrap of a texel index into [0, size).
  int WrapIndex(int i, int size) const {
    switch (wrap_) {
      case Wrap::kRepeat:
        return ((i % size) + size) % size;
      case Wrap::kMirror: {
        const int period = ((i % (2 * size)) + 2 * size) % (2 * size);
        return period >= size ? 2 * size - period - 1 : period;
      }
      case Wrap::kClamp:
        return std::clamp(i, 0, size - 1);
    }
    return 0;
  }

  Vec3 Texel(int x, int y) const {
    x = WrapIndex(x, image_.width), y = WrapIndex(y, image_.height);
    const float* t = &image_.texels[(size_t(y) * size_t(image_.width) + size_t(x)) * size_t(image_.channels)];
    return image_.channels == 3 ? Vec3(t[0], t[1], t[2]) : Vec3(t[0], t[0], t[0]);
  }

  Vec3 Lookup(float u, float v) const {
    if (!bilinear_) return Texel(int(std::floor(u * float(image_.width))), int(std::floor(v * float(image_.height))));
    const float px = u * float(image_.width) - 0.5f, py = v * float(image_.height) - 0.5f;
    const float fx0 = std::floor(px), fy0 = std::floor(py);
    const int x0 = int(fx0), y0 = int(fy0);
    const float fx = px - fx0, fy = py - fy0;
    return (Texel(x0, y0) * (1 - fx) + Texel(x0 + 1, y0) * fx) * (1 - fy) +
           (Texel(x0, y0 + 1) * (1 - fx) + Texel(x0 + 1, y0 + 1) * fx) * fy;
  }

  // Cells of half a texel (a quarter of the texel's area), each weighted by
  // the largest luminance among the texels its lookups read: with bilinear
  // lookups, the 2 × 2 texels whose centres surround it. Large images use
  // one cell per texel and its 3 × 3 neighbours, a looser bound.
  void BuildDistribution() {
    const int width = image_.width, height = image_.height;
    const bool half = int64_t(width) * height <= (int64_t(1) << 20);
    const int cells_x = half ? 2 * width : width, cells_y = half ? 2 * height : height;
    std::vector<float> weights(size_t(cells_x) * size_t(cells_y));
    for (int j = 0; j < cells_y; ++j) {
      for (int i = 0; i < cells_x; ++i) {
        // The texel rows and columns the cell reads: [x0, x1] × [y0, y1].
        int x0 = half ? i / 2 : i, y0 = half ? j / 2 : j, x1 = x0, y1 = y0;
        if (bilinear_ && half) {
          x0 = (i + 1) / 2 - 1, x1 = x0 + 1;
          y0 = (j + 1) / 2 - 1, y1 = y0 + 1;
        } else if (bilinear_) {
          x0 = i - 1, x1 = i + 1, y0 = j - 1, y1 = j + 1;
        }
        float weight = 0;
        for (int y = y0; y <= y1; ++y)
          for (int x = x0; x <= x1; ++x) weight = std::max(weight, yarf::Luminance(Texel(x, y)));
        weights[size_t(j) * size_t(cells_x) + size_t(i)] = weight;
      }
    }
    cells_ = yarf::PiecewiseConstant2D(std::move(weights), cells_x, cells_y);
  }

  float scale_ = 1;
  bool intensity_image_ = false;
  bool bilinear_ = true;
  Wrap wrap_ = Wrap::kRepeat;
  yarf::textures::LinearImage image_;
  float tan_x_ = 1, tan_y_ = 1, plane_area_ = 4;
  Matrix3 linear_, inverse_;
  float abs_det_ = 1;
  yarf::Frame kernel_frame_{Vec3(0, 0, 1)};
  Vec3 forward_{0, 0, 1};
  yarf::PiecewiseConstant2D cells_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Projector>(registrar, "projector", "1.0.0",
                            "Point light projecting an image through a perspective frustum (Mitsuba's projector)");
}
