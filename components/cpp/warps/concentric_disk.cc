// concentric_disk — uniform points of the unit disk
//
// Shirley and Chiu's concentric map of the square onto the unit disk: it
// takes concentric squares to concentric circles, so strata of the square
// stay compact on the disk (the polar map r = √u0 makes slivers).
//
// Signature: [0,1)² → points (x, y) of the unit disk, pdf 1/π per unit
// area; 0 outside the disk. Inverse: exact; points outside the disk map
// to the edge of the square.
//
// Parameters: none (ConcentricDisk::Parameters() below).
#include <array>
#include <cstdint>

#include "square_warp.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

struct ConcentricDisk {
  static constexpr uint32_t kImageDimensions = 2;

  static yarf::ParameterSchema Parameters() { return {}; }
  explicit ConcentricDisk(const yarf::Properties&) {}

  void Sample(float u0, float u1, float* point) const {
    const auto [x, y] = yarf::SampleConcentricDisk(u0, u1);
    point[0] = x;
    point[1] = y;
  }
  float Density(const float* point) const { return yarf::ConcentricDiskPdf(point[0], point[1]); }
  std::array<float, 2> Invert(const float* point) const {
    return yarf::InvertConcentricDisk(point[0], point[1]);
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::SquareWarp<ConcentricDisk>>(
      registrar, "concentric_disk", "1.0.0", "Uniform points of the unit disk (Shirley-Chiu concentric map)");
}
