#include "kernel/light_bvh.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace yarf {
namespace {

float SafeAcos(float c) { return std::acos(std::clamp(c, -1.0f, 1.0f)); }
float SafeSqrt(float x) { return std::sqrt(std::max(0.0f, x)); }

// cos(θa − θb) and sin(θa − θb), clamped to 1 and 0 where θa < θb.
float CosOfDifference(float sin_a, float cos_a, float sin_b, float cos_b) {
  return cos_a > cos_b ? 1.0f : cos_a * cos_b + sin_a * sin_b;
}
float SinOfDifference(float sin_a, float cos_a, float sin_b, float cos_b) {
  return cos_a > cos_b ? 0.0f : sin_a * cos_b - cos_a * sin_b;
}

// The narrowest cone holding cones (wa, cos_a) and (wb, cos_b), found as
// pbrt-v4's DirectionCone Union finds it.
std::pair<Vec3, float> ConeUnion(Vec3 wa, float cos_a, Vec3 wb, float cos_b) {
  const float theta_a = SafeAcos(cos_a), theta_b = SafeAcos(cos_b), theta_d = SafeAcos(Dot(wa, wb));
  if (std::min(theta_d + theta_b, kPi) <= theta_a) return {wa, cos_a};
  if (std::min(theta_d + theta_a, kPi) <= theta_b) return {wb, cos_b};
  const float theta_o = (theta_a + theta_d + theta_b) / 2;
  const Vec3 axis = Cross(wa, wb);
  if (theta_o >= kPi || !(Length(axis) > 1e-7f)) return {wa, -1.0f};
  // wa turned toward wb by θo − θa about their common normal.
  const float theta_r = theta_o - theta_a;
  const Vec3 k = Normalize(axis);
  return {Normalize(wa * std::cos(theta_r) + Cross(k, wa) * std::sin(theta_r)), std::cos(theta_o)};
}

}  // namespace

LightBounds LightBounds::Union(const LightBounds& a, const LightBounds& b) {
  if (a.phi == 0) return b;
  if (b.phi == 0) return a;
  LightBounds u;
  u.lower = Vec3(std::min(a.lower.x, b.lower.x), std::min(a.lower.y, b.lower.y), std::min(a.lower.z, b.lower.z));
  u.upper = Vec3(std::max(a.upper.x, b.upper.x), std::max(a.upper.y, b.upper.y), std::max(a.upper.z, b.upper.z));
  u.phi = a.phi + b.phi;
  std::tie(u.w, u.cos_theta_o) = ConeUnion(a.w, a.cos_theta_o, b.w, b.cos_theta_o);
  u.cos_theta_e = std::min(a.cos_theta_e, b.cos_theta_e);
  u.two_sided = a.two_sided || b.two_sided;
  return u;
}

float LightBounds::Importance(Vec3 p) const {
  const Vec3 centre = Centroid();
  // Distance to the centre, kept from vanishing for points among the lights.
  const float d2 = std::max(Dot(p - centre, p - centre), Length(upper - lower) / 2);
  // The directions from p to the bounds: a cone of half-angle θb (all of
  // them from inside the bounding sphere).
  const float radius2 = Dot(upper - centre, upper - centre), distance2 = Dot(p - centre, p - centre);
  const float cos_b = distance2 < radius2 ? -1.0f : SafeSqrt(1 - radius2 / distance2);
  const float sin_b = SafeSqrt(1 - cos_b * cos_b);
  // The angle from the normals' axis to p, less the normals' spread and
  // the bounds' extent: the smallest angle any emitting normal can make
  // with a direction toward p.
  const float to_p = Length(p - centre);
  float cos_w = to_p > 0 ? Dot(w, (p - centre) / to_p) : 1.0f;
  if (two_sided) cos_w = std::abs(cos_w);
  const float sin_w = SafeSqrt(1 - cos_w * cos_w);
  const float sin_o = SafeSqrt(1 - cos_theta_o * cos_theta_o);
  const float cos_x = CosOfDifference(sin_w, cos_w, sin_o, cos_theta_o);
  const float sin_x = SinOfDifference(sin_w, cos_w, sin_o, cos_theta_o);
  const float cos_closest = CosOfDifference(sin_x, cos_x, sin_b, cos_b);
  if (cos_closest <= cos_theta_e) return 0;
  return std::max(0.0f, phi * cos_closest / d2);
}

LightBvh::LightBvh(const std::vector<LightBounds>& lights) {
  trails_.assign(lights.size(), kNoTrail);
  std::vector<std::pair<uint32_t, LightBounds>> kept;
  for (uint32_t i = 0; i < lights.size(); ++i)
    if (lights[i].phi > 0 && std::isfinite(lights[i].phi)) kept.emplace_back(i, lights[i]);
  if (!kept.empty()) Build(kept, 0, kept.size(), 0, 0);
}

uint32_t LightBvh::Build(std::vector<std::pair<uint32_t, LightBounds>>& lights, size_t begin, size_t end,
                         uint64_t trail, int depth) {
  const uint32_t node = uint32_t(nodes_.size());
  nodes_.emplace_back();
  if (end - begin == 1 || depth >= 63) {
    // A leaf per light; past 63 levels (never, for a median split of
    // fewer than 2^63 lights) the rest would share one.
    nodes_[node] = {lights[begin].second, lights[begin].first, true};
    trails_[lights[begin].first] = trail;
    return node;
  }
  // Split at the median of the centroids along their widest axis.
  Vec3 lo = lights[begin].second.Centroid(), hi = lo;
  for (size_t i = begin; i < end; ++i) {
    const Vec3 c = lights[i].second.Centroid();
    lo = Vec3(std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z));
    hi = Vec3(std::max(hi.x, c.x), std::max(hi.y, c.y), std::max(hi.z, c.z));
  }
  const Vec3 extent = hi - lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
  const size_t middle = begin + (end - begin) / 2;
  std::nth_element(lights.begin() + long(begin), lights.begin() + long(middle), lights.begin() + long(end),
                   [axis](const auto& a, const auto& b) { return a.second.Centroid()[axis] < b.second.Centroid()[axis]; });
  Build(lights, begin, middle, trail, depth + 1);
  const uint32_t second = Build(lights, middle, end, trail | (uint64_t(1) << depth), depth + 1);
  nodes_[node].bounds = LightBounds::Union(nodes_[node + 1].bounds, nodes_[second].bounds);
  nodes_[node].index = second;
  return node;
}

float LightBvh::FirstChildOdds(uint32_t node, Vec3 p) const {
  const float first = nodes_[node + 1].bounds.Importance(p), second = nodes_[nodes_[node].index].bounds.Importance(p);
  return first + second > 0 ? first / (first + second) : -1.0f;
}

std::optional<std::pair<uint32_t, float>> LightBvh::Sample(Vec3 p, float u, float& u_rest) const {
  if (nodes_.empty()) return std::nullopt;
  uint32_t node = 0;
  float pmf = 1;
  while (!nodes_[node].leaf) {
    const float odds = FirstChildOdds(node, p);
    if (odds < 0) return std::nullopt;
    if (u < odds) {
      u = std::min(u / odds, 0x1.fffffep-1f);
      pmf *= odds;
      node = node + 1;
    } else {
      u = std::clamp((u - odds) / (1 - odds), 0.0f, 0x1.fffffep-1f);
      pmf *= 1 - odds;
      node = nodes_[node].index;
    }
  }
  if (node == 0 && !(nodes_[0].bounds.Importance(p) > 0)) return std::nullopt;
  if (!(pmf > 0)) return std::nullopt;
  u_rest = u;
  return std::pair{nodes_[node].index, pmf};
}

float LightBvh::Pmf(Vec3 p, uint32_t light) const {
  if (light >= trails_.size() || trails_[light] == kNoTrail) return 0;
  uint64_t trail = trails_[light];
  uint32_t node = 0;
  float pmf = 1;
  while (!nodes_[node].leaf) {
    const float odds = FirstChildOdds(node, p);
    if (odds < 0) return 0;
    const bool second = trail & 1;
    trail >>= 1;
    pmf *= second ? 1 - odds : odds;
    node = second ? nodes_[node].index : node + 1;
  }
  if (node == 0 && !(nodes_[0].bounds.Importance(p) > 0)) return 0;
  return pmf;
}

}  // namespace yarf
