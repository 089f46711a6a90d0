// uniform_triangle — uniform points of a triangle, as barycentrics
//
// Heitz's low-distortion map (2019) folds the square onto the triangle
// without the stretching of the square-root map. The image is the
// barycentric coordinates (b0, b1, b2) of the point (p = b0·p0 + b1·p1 +
// b2·p2), so one warp serves every triangle: the caller applies the
// vertices, and divides the pdf by twice the triangle's area to get it per
// unit of that area.
//
// Signature: [0,1)² → barycentrics (b0, b1, b2), bi ≥ 0, b0 + b1 + b2 = 1.
// The pdf is 2 with respect to area in the (b0, b1) plane (the standard
// triangle has area 1/2); 0 off the triangle (a negative coordinate, or
// coordinates that do not sum to 1). Inverse: exact; only b0 and b1 are
// read.
//
// Parameters: none (UniformTriangle::Parameters() below).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "square_warp.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

// The standard triangle (0,0), (1,0), (0,1) of the (b0, b1) plane.
constexpr float kBarycentricArea = 0.5f;

struct UniformTriangle {
  static constexpr uint32_t kImageDimensions = 3;

  static yarf::ParameterSchema Parameters() { return {}; }
  explicit UniformTriangle(const yarf::Properties&) {}

  void Sample(float u0, float u1, float* b) const {
    const auto [b0, b1, b2] = yarf::SampleUniformTriangle(u0, u1);
    b[0] = b0;
    b[1] = b1;
    // 1 - b0 - b1 may round a hair below 0.
    b[2] = std::max(0.0f, b2);
  }
  // Tolerates the rounding of b2 = 1 - b0 - b1 in float.
  float Density(const float* b) const {
    constexpr float kSlack = 1e-6f;
    const bool inside = b[0] >= -kSlack && b[1] >= -kSlack && b[2] >= -kSlack &&
                        std::abs(b[0] + b[1] + b[2] - 1.0f) <= 4 * kSlack;
    return inside ? yarf::UniformTrianglePdf(kBarycentricArea) : 0.0f;
  }
  std::array<float, 2> Invert(const float* b) const { return yarf::InvertUniformTriangle(b[0], b[1]); }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::SquareWarp<UniformTriangle>>(
      registrar, "uniform_triangle", "1.0.0", "Uniform points of a triangle as barycentrics (Heitz 2019)");
}
