// Progressive refinement radiosity (Cohen, Chen, Wallace & Greenberg 1988)
// on a PatchMesh: the shooter side with the most unshot power sends it to
// every element, with form factors cast as rays (Wallace, Elmquist &
// Haines 1989).
//
// Every element has two sides, front (its normal's) and back, each with
// its own reflectance, emission and radiosity: a side is element 2e
// (front) or 2e+1 (back); shooter sides likewise. Radiosities are radiant
// exitances, W·m⁻², per RGB channel.
//
// Form factors: from the centre x of each receiving element to S sample
// points y on the shooter (centroids of its cells), each standing for
// ΔA = A_s/S: F(x → ΔA) = ΔA cos θ_y cos θ_x /(π r² + ΔA), the disc
// approximation, zero when the ray between them is occluded. The
// approximation holds while the disc is small against r: receivers near
// the shooter take up to 4³ times more samples, until ΔA < kNearArea ×
// (distance to the shooter's edge)². The side of the receiver that faces
// y receives. By reciprocity the shooter sends ΔB_s A_x F(x → s) of its
// power to the element; were the sum over all elements more than all of
// it, every share is scaled down so that no power is created. What the
// sum falls short of 1 escapes (through an opening, or the estimate's
// error). The elements' vertices receive likewise, for display only.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "radiosity_mesh.h"
#include "radiosity_shading.h"

namespace yarf::radiosity {

// An RGB sum of many small terms, kept in double so that none is lost.
struct Power {
  double rgb[3] = {0, 0, 0};
  Power& operator+=(Vec3 v) {
    rgb[0] += v.x, rgb[1] += v.y, rgb[2] += v.z;
    return *this;
  }
  double Sum() const { return rgb[0] + rgb[1] + rgb[2]; }
};

// Powers, W per channel, since the solve began.
struct EnergyTotals {
  Power emitted, absorbed, escaped, unshot;
  uint64_t shots = 0, rays = 0;
  // Shots whose form factors summed to more than 1 and were scaled down.
  uint64_t scaled_shots = 0;
};

struct SolverSettings {
  double tolerance = 1e-3;  // stop when unshot < tolerance × emitted
  uint64_t max_shots = 100000;
  uint32_t sample_level = 1;  // 4^sample_level points per shooter
};

class ProgressiveSolver {
 public:
  // reflectance and emission: per element side (2 per element); the
  // vertices receive too (for display) but do not shoot.
  ProgressiveSolver(const PatchMesh& mesh, const VertexSet& vertices, std::vector<Vec3> reflectance,
                    std::vector<Vec3> emission)
      : mesh_(mesh),
        vertices_(vertices),
        vertex_reflectance_(vertices.Mean(mesh, reflectance)),
        vertex_radiosity_(vertices.Mean(mesh, emission)),
        reflectance_(std::move(reflectance)),
        emission_(emission),
        radiosity_(emission),
        unshot_(std::move(emission)),
        reached_(radiosity_.size()),
        shooter_power_(2 * mesh.shooters().size()) {
    const std::vector<Patch>& elements = mesh_.elements();
    first_member_.assign(mesh.shooters().size() + 1, 0);
    for (const Patch& e : elements) ++first_member_[e.shooter + 1];
    for (size_t s = 0; s < mesh.shooters().size(); ++s) first_member_[s + 1] += first_member_[s];
    members_.resize(elements.size());
    std::vector<uint32_t> fill(first_member_.begin(), first_member_.end() - 1);
    for (uint32_t e = 0; e < elements.size(); ++e) members_[fill[elements[e].shooter]++] = e;
    for (uint32_t k = 0; k < unshot_.size(); ++k) {
      const Vec3 power = unshot_[k] * elements[k / 2].area;
      totals_.emitted += power;
      shooter_power_[2 * elements[k / 2].shooter + k % 2] += Sum(power);
      reached_[k] = Sum(power) > 0;
    }
  }

  // Shoots until the unshot power is below tolerance × emitted, or
  // max_shots.
  void Solve(const SceneView& scene, const SolverSettings& settings) {
    const double emitted = totals_.emitted.Sum();
    while (totals_.shots < settings.max_shots) {
      const auto largest = std::max_element(shooter_power_.begin(), shooter_power_.end());
      if (largest == shooter_power_.end() || *largest <= 0) break;
      double unshot = 0;
      for (double p : shooter_power_) unshot += p;
      if (unshot <= settings.tolerance * emitted) break;
      Shoot(scene, uint32_t(largest - shooter_power_.begin()), settings.sample_level);
    }
    totals_.unshot = Power();
    for (size_t k = 0; k < unshot_.size(); ++k) totals_.unshot += unshot_[k] * mesh_.elements()[k / 2].area;
  }

  const EnergyTotals& totals() const { return totals_; }
  // Per element side: total radiosity (emission included) and ρ.
  const std::vector<Vec3>& radiosity() const { return radiosity_; }
  const std::vector<Vec3>& reflectance() const { return reflectance_; }
  // Per vertex side: total radiosity (emission included).
  const std::vector<Vec3>& vertex_radiosity() const { return vertex_radiosity_; }

  // Cohen et al.'s ambient term: the unshot power spread evenly over the
  // sides light has reached, and interreflected by their mean ρ, as an
  // exitance that each side reflects (× its ρ) until the solve is done.
  Vec3 Ambient() const {
    double area = 0;
    Vec3 reflected;
    for (size_t k = 0; k < radiosity_.size(); ++k) {
      if (!reached_[k]) continue;
      const float a = mesh_.elements()[k / 2].area;
      area += a;
      reflected += reflectance_[k] * a;
    }
    if (!(area > 0)) return {};
    const Vec3 mean_reflectance = reflected / float(area);
    auto channel = [&](int c) {
      return float(totals_.unshot.rgb[c] / area / std::max(1e-3f, 1 - mean_reflectance[c]));
    };
    return {channel(0), channel(1), channel(2)};
  }

  // Σ (1−ρ)/ρ (B − E) A: the power absorbed, recomputed from the final
  // radiosities as a check on the shots' bookkeeping (a channel with
  // ρ = 0 keeps no trace of what it absorbed: it counts 0 here).
  Power AbsorbedBySolution() const {
    Power absorbed;
    for (size_t k = 0; k < radiosity_.size(); ++k) {
      const Vec3 reflected = radiosity_[k] - emission_[k];
      for (int c = 0; c < 3; ++c) {
        const double rho = reflectance_[k][c];
        if (rho > 0) absorbed.rgb[c] += (1 - rho) / rho * reflected[c] * mesh_.elements()[k / 2].area;
      }
    }
    return absorbed;
  }

 private:
  static double Sum(Vec3 v) { return double(v.x) + double(v.y) + double(v.z); }

  // Shooter side `side_index` = 2·shooter + (0 front, 1 back) sends its
  // unshot power to every element.
  void Shoot(const SceneView& scene, uint32_t side_index, uint32_t sample_level) {
    const std::vector<Patch>& elements = mesh_.elements();
    const uint32_t s = side_index / 2, side = side_index % 2;
    const Patch& shooter = mesh_.shooters()[s];
    const Vec3 normal = side ? -shooter.normal : shooter.normal;
    // The shooter's unshot radiosity: its elements' unshot power over its area.
    Vec3 power;
    for (uint32_t m = first_member_[s]; m < first_member_[s + 1]; ++m) {
      const uint32_t k = 2 * members_[m] + side;
      power += unshot_[k] * elements[members_[m]].area;
      unshot_[k] = Vec3();
    }
    shooter_power_[side_index] = 0;
    ++totals_.shots;
    const Vec3 delta_b = power / shooter.area;

    // Finer sample sets for receivers near the shooter, where one sample's
    // disc would be large against its distance.
    std::vector<std::vector<Vec3>> sample_sets;
    for (uint32_t level = sample_level; level <= sample_level + kExtraSampleLevels; ++level)
      sample_sets.push_back(PatchMesh::SamplePoints(shooter, level));
    float reach = 0;  // the shooter's radius about its centre
    for (const Vec3& c : shooter.corner) reach = std::max(reach, Length(c - shooter.centre));
    // Form factors of element sides at [0, 2E), of vertex sides after.
    form_factor_.assign(2 * elements.size() + 2 * vertices_.Count(), 0.0f);
    // Shadow rays toward the shooter, cast a batch at a time.
    struct Rays {
      std::vector<Ray> rays;
      std::vector<uint32_t> receivers;
      std::vector<float> shares;
    };
    std::atomic<uint64_t> rays_cast = 0;
    auto flush = [&](Rays& batch) {
      std::vector<uint8_t> occluded(batch.rays.size());
      scene.Occluded(batch.rays, occluded);
      for (size_t q = 0; q < batch.rays.size(); ++q)
        if (!occluded[q]) form_factor_[batch.receivers[q]] += batch.shares[q];
      rays_cast.fetch_add(batch.rays.size(), std::memory_order_relaxed);
      batch.rays.clear(), batch.receivers.clear(), batch.shares.clear();
    };
    // Samples the shooter from point x (normal n, near the shooter within
    // `size`) into form_factor_[index] (front) and [index + 1] (back).
    auto receive = [&](Vec3 x, Vec3 n, float size, uint32_t index, Rays& batch) {
      // Samples until each one's area is below kNearArea × the squared
      // distance to the shooter (its edge; at least the receiver's size).
      const float gap = std::max(Length(x - shooter.centre) - reach, size);
      size_t set = 0;
      while (set + 1 < sample_sets.size() &&
             shooter.area / float(sample_sets[set].size()) > kNearArea * gap * gap)
        ++set;
      const std::vector<Vec3>& samples = sample_sets[set];
      const float sample_area = shooter.area / float(samples.size());
      for (const Vec3& y : samples) {
        const Vec3 d = x - y;
        const float r2 = Dot(d, d);
        if (!(r2 > 0)) continue;
        const float r = std::sqrt(r2);
        const float cos_shooter = Dot(normal, d) / r;
        const float cos_receiver = -Dot(n, d) / r;
        if (cos_shooter <= 0 || cos_receiver == 0) continue;
        batch.rays.push_back(ShadowRay(x, n, y));
        batch.receivers.push_back(index + (cos_receiver > 0 ? 0 : 1));
        batch.shares.push_back(sample_area * cos_shooter * std::abs(cos_receiver) / (kPi * r2 + sample_area));
        if (batch.rays.size() >= kRayBatch) flush(batch);
      }
    };
    // Receivers r < E are elements, the rest vertices. Each receiver's
    // form factors are its own: ranges of receivers run on the job's
    // threads, and each sums its samples in the same order on any.
    const uint32_t vertex_base = uint32_t(2 * elements.size());
    const uint32_t receivers = uint32_t(elements.size() + vertices_.Count());
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, receivers, kReceiversPerTask),
                      [&](const tbb::blocked_range<uint32_t>& range) {
                        Rays batch;
                        for (uint32_t r = range.begin(); r != range.end(); ++r) {
                          if (r < elements.size()) {
                            const Patch& e = elements[r];
                            if (e.shooter != s) receive(e.centre, e.normal, std::sqrt(e.area), 2 * r, batch);
                          } else {
                            const uint32_t v = r - uint32_t(elements.size());
                            receive(vertices_.position[v], vertices_.normal[v], vertices_.size[v],
                                    vertex_base + 2 * v, batch);
                          }
                        }
                        flush(batch);
                      });
    totals_.rays += rays_cast.load();

    double sum = 0;  // Σ F(s → x) over the receivers
    for (size_t k = 0; k < vertex_base; ++k)
      if (form_factor_[k] > 0) sum += double(form_factor_[k]) * elements[k / 2].area / shooter.area;
    const float scale = sum > 1 ? float(1 / sum) : 1.0f;
    if (sum > 1) ++totals_.scaled_shots;
    totals_.escaped += power * float(1 - std::min(sum, 1.0));
    for (uint32_t k = vertex_base; k < form_factor_.size(); ++k) {
      const uint32_t v = k - vertex_base;
      vertex_radiosity_[v] += vertex_reflectance_[v] * delta_b * (form_factor_[k] * scale);
    }
    for (uint32_t k = 0; k < vertex_base; ++k) {
      if (!(form_factor_[k] > 0)) continue;
      const Patch& receiver = elements[k / 2];
      const Vec3 irradiance = delta_b * (form_factor_[k] * scale);  // received power / A
      const Vec3 reflected = reflectance_[k] * irradiance;
      totals_.absorbed += (irradiance - reflected) * receiver.area;
      radiosity_[k] += reflected;
      unshot_[k] += reflected;
      reached_[k] = true;
      shooter_power_[2 * receiver.shooter + k % 2] += Sum(reflected) * receiver.area;
    }
  }

  static constexpr size_t kRayBatch = 1 << 16;
  static constexpr uint32_t kReceiversPerTask = 256;
  static constexpr uint32_t kExtraSampleLevels = 3;
  static constexpr float kNearArea = 0.1f;

  const PatchMesh& mesh_;
  const VertexSet& vertices_;
  std::vector<Vec3> vertex_reflectance_, vertex_radiosity_;
  std::vector<Vec3> reflectance_, emission_, radiosity_, unshot_;
  std::vector<uint8_t> reached_;
  // Unshot power of each shooter side, summed over channels.
  std::vector<double> shooter_power_;
  // Elements of shooter s: members_[first_member_[s] .. first_member_[s+1]).
  std::vector<uint32_t> first_member_, members_;
  std::vector<float> form_factor_;  // per element and vertex side, of the current shot
  EnergyTotals totals_;
};

}  // namespace yarf::radiosity
