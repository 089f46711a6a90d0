// A bounding volume hierarchy over the lights that have a place in the
// scene (surfaces, points), for choosing one by what it may give a point:
// pbrt-v4's BVHLightSampler (Conty Estevez & Kulla 2018). Each node bounds
// its lights' positions, total power and emission directions; from a
// point, the walk down picks a child in proportion to an importance that
// is never zero where a light could reach the point, so the choice is
// unbiased, and the probability of a light is the product of the choices
// on its path, found again from its bit trail.
#pragma once

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "yarf/vecmath.h"

namespace yarf {

// What a light (or a node's lights) may send where: within `lower`–`upper`,
// power `phi`, emitting from normals within cos_theta_o of axis `w` (−1:
// every direction) into directions within cos_theta_e of those normals.
struct LightBounds {
  Vec3 lower, upper;
  float phi = 0;
  Vec3 w{0, 0, 1};
  float cos_theta_o = -1, cos_theta_e = 0;
  bool two_sided = true;

  // The bound of both (pbrt-v4's Union, the cone of both cones).
  static LightBounds Union(const LightBounds& a, const LightBounds& b);
  // An upper bound of what these lights give point p, up to a common
  // factor; 0 only where none of them can reach p.
  float Importance(Vec3 p) const;
  Vec3 Centroid() const { return (lower + upper) * 0.5f; }
};

class LightBvh {
 public:
  LightBvh() = default;
  // `lights[i]` bounds the caller's light i; lights of no power are left out.
  explicit LightBvh(const std::vector<LightBounds>& lights);

  bool Empty() const { return nodes_.empty(); }
  // A light for point p and its probability, and u_rest: u rescaled
  // within the choice; none when no light can reach p.
  std::optional<std::pair<uint32_t, float>> Sample(Vec3 p, float u, float& u_rest) const;
  // The probability that Sample picks `light` for p.
  float Pmf(Vec3 p, uint32_t light) const;

 private:
  struct Node {
    LightBounds bounds;
    // A leaf: the light; an inner node: its second child (the first
    // follows it).
    uint32_t index = 0;
    bool leaf = false;
  };
  uint32_t Build(std::vector<std::pair<uint32_t, LightBounds>>& lights, size_t begin, size_t end, uint64_t trail,
                 int depth);
  // The probability of the first child of inner node `node` for p.
  float FirstChildOdds(uint32_t node, Vec3 p) const;

  std::vector<Node> nodes_;
  // Per light: the path to its leaf, bit d set where the walk takes the
  // second child at depth d; kNoTrail for lights left out.
  static constexpr uint64_t kNoTrail = ~uint64_t(0);
  std::vector<uint64_t> trails_;
};

}  // namespace yarf
