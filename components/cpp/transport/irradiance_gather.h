// Making one irradiance cache record: the hemisphere gather over M×N
// cosine-stratified cells (Ward, Rubinstein & Clear 1988) and the
// rotational and translational gradients from the same cells (Ward &
// Heckbert 1992). Deterministic: the cell jitter and the light samples
// are hashes of the record's index.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "irradiance_records.h"
#include "yarf/support/wavefront.h"
#include "yarf/support/hash.h"

namespace yarf {

// A point where the cache is wanted: position and the shading normal on
// the side it is seen from; the geometric normal for leaving the surface.
struct SurfacePoint {
  Vec3 position, normal, geometric_normal;
};

struct GatherSettings {
  uint32_t gather_rays = 512;
  // The clamp of the harmonic mean distance R, in scene units.
  float min_radius = 0, max_radius = 0;
};

// A deterministic number in [0,1): a hash of a salt and three integers.
inline float Uniform(uint64_t salt, uint64_t a, uint64_t b, uint64_t c) {
  return ToUnitFloat(uint32_t(Hash(salt, a, b, c) >> 32));
}

inline constexpr uint64_t kGatherSalt = 0x6972632d67617468ull;

// Ward & Heckbert's translational gradient: the change of each cell
// boundary's solid angle as p moves, times the radiance difference
// across it, over the boundaries between rings (θ) and between wedges
// (φ). Distances are kept above min spacing so that a gather ray ending
// in a corner does not make the gradient explode.
inline std::array<Vec3, 3> TranslationalGradient(const Frame& frame, uint32_t m, uint32_t n,
                                                 const std::vector<Vec3>& radiance,
                                                 const std::vector<float>& distance, float min_radius) {
  std::array<Vec3, 3> gradient{};
  auto at = [&](uint32_t j, uint32_t k) { return j * n + k; };
  auto nearer = [&](uint32_t a, uint32_t b) { return std::max(std::min(distance[a], distance[b]), min_radius); };
  auto add = [&](Vec3 axis, float scale, Vec3 difference) {
    for (int ch = 0; ch < 3; ++ch) gradient[ch] += axis * (scale * difference[ch]);
  };
  for (uint32_t k = 0; k < n; ++k) {
    const float phi = 2 * kPi * (float(k) + 0.5f) / float(n);
    const Vec3 outward = frame.ToWorld({std::cos(phi), std::sin(phi), 0});
    for (uint32_t j = 1; j < m; ++j) {
      const float sin2 = float(j) / float(m);
      const float scale = (2 * kPi / float(n)) * std::sqrt(sin2) * (1 - sin2) / nearer(at(j, k), at(j - 1, k));
      add(outward, scale, radiance[at(j, k)] - radiance[at(j - 1, k)]);
    }
    const float boundary = 2 * kPi * float(k) / float(n);
    const Vec3 across = frame.ToWorld({-std::sin(boundary), std::cos(boundary), 0});
    const uint32_t previous = (k + n - 1) % n;
    for (uint32_t j = 0; j < m; ++j) {
      const float scale = (std::sqrt(float(j + 1) / float(m)) - std::sqrt(float(j) / float(m))) /
                          nearer(at(j, k), at(j, previous));
      add(across, scale, radiance[at(j, k)] - radiance[at(j, previous)]);
    }
  }
  return gradient;
}

// A record at p: M×N cosine-stratified gather rays, the direct light
// their hits reflect toward p, and Ward & Heckbert's gradients.
inline IrradianceRecord GatherRecord(const SceneView& scene, const SurfacePoint& p, uint64_t index,
                                     const GatherSettings& settings) {
  const uint32_t m = std::max<uint32_t>(2, uint32_t(std::lround(std::sqrt(float(settings.gather_rays) / kPi))));
  const uint32_t n = std::max<uint32_t>(3, settings.gather_rays / m);
  const Frame frame(p.normal);
  const float time = scene.ShutterTime(0.5f);
  std::vector<Ray> rays(size_t(m) * n);
  std::vector<Vec3> directions(rays.size());
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t k = 0; k < n; ++k) {
      const uint32_t cell = j * n + k;
      const float sin2 = (float(j) + Uniform(kGatherSalt, index, cell, 0)) / float(m);
      const float phi = 2 * kPi * (float(k) + Uniform(kGatherSalt, index, cell, 1)) / float(n);
      const float sin = std::sqrt(sin2), cos = std::sqrt(std::max(0.0f, 1 - sin2));
      directions[cell] = Normalize(frame.ToWorld({sin * std::cos(phi), sin * std::sin(phi), cos}));
      rays[cell].time = time;
      Redirect(rays[cell], p.position, p.geometric_normal, directions[cell]);
    }
  std::vector<Hit> hits(rays.size());
  scene.Intersect(rays, hits);

  std::vector<float> distance(rays.size(), kInfinity);
  std::vector<Vec3> radiance(rays.size());
  // The light at each gather ray's hit: one light sample there (the
  // emitters and the environment the rays see are direct light at p,
  // which p's own light samples count).
  std::vector<LightConnection> connections;
  std::vector<uint32_t> lit;
  std::vector<Vec3> from;
  std::vector<float> u;
  for (uint32_t c = 0; c < rays.size(); ++c) {
    if (!hits[c].Found()) continue;
    distance[c] = hits[c].t;
    const uint32_t material = scene.MaterialOf(hits[c].shape);
    if (!TakesLightSamples(scene, scene.Material(material))) continue;
    const ShadingPoint at(scene, hits[c], rays[c]);
    connections.push_back({material, at.position, at.ng, at.frame, at.wi, at.site, time, {}});
    lit.push_back(c);
    from.push_back(at.position);
    for (uint32_t d = 2; d < 5; ++d) u.push_back(Uniform(kGatherSalt, index, c, d));
  }
  std::vector<LightDirection> lights(from.size());
  scene.SampleLightsFrom(from, u, lights);
  for (size_t q = 0; q < lights.size(); ++q) connections[q].light = lights[q];
  const std::vector<Vec3> direct = DirectLight(scene, connections);
  for (size_t q = 0; q < lit.size(); ++q) radiance[lit[q]] = direct[q];

  IrradianceRecord r;
  r.position = p.position;
  r.normal = p.normal;
  const float cells = float(m * n);
  float inverse_distances = 0;
  for (uint32_t c = 0; c < rays.size(); ++c) {
    // Each cell has probability 1/(MN) under cos/π: E = π/(MN) Σ L.
    r.irradiance += radiance[c] * (kPi / cells);
    inverse_distances += 1.0f / distance[c];
    // ∇r E = ∫ L (n × ω) dω, estimated as π/(MN) Σ L (n × ω)/cos θ.
    const float cos = std::max(Dot(directions[c], p.normal), 1e-3f);
    const Vec3 axis = Cross(p.normal, directions[c]) * (kPi / (cells * cos));
    for (int ch = 0; ch < 3; ++ch) r.rotational[ch] += axis * radiance[c][ch];
  }
  r.radius = std::clamp(inverse_distances > 0 ? cells / inverse_distances : settings.max_radius, settings.min_radius,
                        settings.max_radius);
  r.translational = TranslationalGradient(frame, m, n, radiance, distance, settings.min_radius);
  return r;
}

}  // namespace yarf
