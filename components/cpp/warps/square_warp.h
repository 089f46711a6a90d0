// The Warp boilerplate of this folder's warps from [0,1)². SquareWarp<Map>
// loops over a batch of points and leaves each point to Map, which has
//   static constexpr uint32_t kImageDimensions
//   static yarf::ParameterSchema Parameters()  the parameters it reads
//   explicit Map(const yarf::Properties&)      reads and checks them
//   void Sample(float u0, float u1, float* point) const
//   float Density(const float* point) const    0 off the image
//   std::array<float, 2> Invert(const float* point) const
// A map without an inverse leaves out Invert and names itself in a static
// Name(), which the error of Inverse quotes.
// DirectionWarp<Map> is the same for maps onto unit vectors, whose Map
// deals in yarf::Vec3 instead of float* (and gets Density only for unit
// vectors: off the unit sphere the density is 0). The warp declares its
// map's parameters as its own.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "yarf/math.h"
#include "yarf/parameters.h"
#include "yarf/vecmath.h"
#include "yarf/support/warps.h"

namespace yarf {

template <typename Map>
class SquareWarp final : public Warp {
 public:
  static ParameterSchema Parameters() { return Map::Parameters(); }

  explicit SquareWarp(const Properties& props) : map_(props) {}

  uint32_t DomainDimensions() const override { return 2; }
  uint32_t ImageDimensions() const override { return kImage; }

  void Forward(std::span<const float> uniform, std::span<float> points,
               std::span<float> pdf) const override {
    const size_t count = uniform.size() / 2;
    for (size_t k = 0; k < count; ++k) {
      float* point = &points[kImage * k];
      map_.Sample(uniform[2 * k], uniform[2 * k + 1], point);
      pdf[k] = map_.Density(point);
    }
  }

  void Inverse(std::span<const float> points, std::span<float> uniform,
               std::span<float> pdf) const override {
    if constexpr (requires(const Map& map, const float* point) { map.Invert(point); }) {
      const size_t count = points.size() / kImage;
      for (size_t k = 0; k < count; ++k) {
        const float* point = &points[kImage * k];
        const auto [u0, u1] = map_.Invert(point);
        uniform[2 * k] = u0;
        uniform[2 * k + 1] = u1;
        pdf[k] = map_.Density(point);
      }
    } else {
      throw Error(std::string(Map::Name()) + " has no inverse");
    }
  }

  void Pdf(std::span<const float> points, std::span<float> pdf) const override {
    const size_t count = points.size() / kImage;
    for (size_t k = 0; k < count; ++k) pdf[k] = map_.Density(&points[kImage * k]);
  }

 private:
  static constexpr uint32_t kImage = Map::kImageDimensions;

  Map map_;
};

// A map of directions as a map of points: unit vectors stored as three
// floats, with density 0 off the unit sphere.
template <typename Directions>
class OntoSphere {
 public:
  static constexpr uint32_t kImageDimensions = 3;

  static ParameterSchema Parameters() { return Directions::Parameters(); }

  explicit OntoSphere(const Properties& props) : directions_(props) {}

  void Sample(float u0, float u1, float* w) const { directions_.Sample(u0, u1).Store(w); }
  float Density(const float* w) const {
    const Vec3 v = Vec3::Load(w);
    return OnUnitSphere(v) ? directions_.Density(v) : 0.0f;
  }
  std::array<float, 2> Invert(const float* w) const
    requires requires(const Directions& d, Vec3 v) { d.Invert(v); }
  {
    return directions_.Invert(Vec3::Load(w));
  }
  static const char* Name() { return Directions::Name(); }

 private:
  Directions directions_;
};

template <typename Directions>
using DirectionWarp = SquareWarp<OntoSphere<Directions>>;

}  // namespace yarf
