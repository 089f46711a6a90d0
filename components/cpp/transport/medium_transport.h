// What the transports that know media share: a path's weight with its
// per-channel density ratios (pbrt-v4's β, r_u, r_l), delta tracking at a
// tentative collision, the transmittance of shadow rays by ratio tracking
// through media and null boundaries, and the medium a point lies in.
#pragma once

#include <algorithm>
#include <span>
#include <vector>

#include "null_tracking.h"
#include "yarf/support/wavefront.h"

namespace yarf {

// A path through media: its weight and the densities of the path so far
// in each channel relative to the hero's, by the unidirectional sampling
// that made it (r_u) and as if its last vertex had been found by light
// sampling (r_l). A contribution is divided by the channels' mean of the
// ratios that apply: the balance heuristic over hero channels.
struct SpectralPath {
  Vec3 beta{1, 1, 1};
  Vec3 r_u{1, 1, 1}, r_l{1, 1, 1};
  uint32_t hero = 0;
  WalkRandom random;

  // The hero chosen uniformly among the channels.
  void ChooseHero() { hero = std::min(2u, uint32_t(3 * random.Next())); }
  bool Alive() const { return MaxComponent(beta) > 0 && MaxComponent(r_u) > 0; }
  // Reached the end of a walk without a real collision: the hero's
  // probability of that, exp(-σ_maj·Δt) in its channel, is divided out.
  // False when it was zero.
  bool Pass(Vec3 transmittance) {
    const float hero_channel = transmittance[int(hero)];
    if (!(hero_channel > 0)) return false;
    beta *= transmittance / hero_channel;
    r_u *= transmittance / hero_channel;
    r_l *= transmittance / hero_channel;
    return true;
  }
};

inline Vec3 NonNegative(Vec3 v) { return {std::max(v.x, 0.0f), std::max(v.y, 0.0f), std::max(v.z, 0.0f)}; }

// What delta tracking makes of a tentative collision.
enum class CollisionEvent { kNull, kScatter, kAbsorb };

// Delta tracking at a tentative collision (pbrt-v4's VolPathIntegrator):
// absorption, real scattering or a null collision chosen by the hero
// channel's coefficients, the path's weight and ratios updated. A null
// collision that leaves the path without weight absorbs it.
inline CollisionEvent DeltaTrack(SpectralPath& p, const Collision& c) {
  const int h = int(p.hero);
  const float sigma_maj = c.sigma_maj[h];
  const float p_absorb = c.sigma_a[h] / sigma_maj, p_scatter = c.sigma_s[h] / sigma_maj;
  const float p_null = std::max(0.0f, 1 - p_absorb - p_scatter);
  const float u = p.random.Next() * (p_absorb + p_scatter + p_null);
  if (u < p_absorb) {
    p.beta = Vec3();
    return CollisionEvent::kAbsorb;
  }
  if (u < p_absorb + p_scatter) {
    const float pdf = c.transmittance_maj[h] * c.sigma_s[h];
    p.beta *= c.transmittance_maj * c.sigma_s / pdf;
    p.r_u *= c.transmittance_maj * c.sigma_s / pdf;
    return CollisionEvent::kScatter;
  }
  const Vec3 sigma_n = NonNegative(c.sigma_maj - c.sigma_a - c.sigma_s);
  const float pdf = c.transmittance_maj[h] * sigma_n[h];
  if (!(pdf > 0)) {
    p.beta = Vec3();
    return CollisionEvent::kAbsorb;
  }
  p.beta *= c.transmittance_maj * sigma_n / pdf;
  p.r_u *= c.transmittance_maj * sigma_n / pdf;
  p.r_l *= c.transmittance_maj * c.sigma_maj / pdf;
  return p.Alive() ? CollisionEvent::kNull : CollisionEvent::kAbsorb;
}

// What a walk through a medium moves: its ray, the medium it is in and
// the path weight delta tracking updates.
struct WalkState {
  const Ray& ray;
  uint32_t medium;
  SpectralPath& path;
};

// Walks the paths `active` that are in a medium through it, up to their
// hits (hits[k] for active[k]; a miss, to the ray's tfar): one batch per
// medium, delta tracking at every tentative collision. `state(i)` gives
// path i's WalkState; at_collision(i, collision) sees each collision
// before it is tracked (a medium's emission), on_scatter(i, collision)
// each real scattering, which ends the path's walk. Returns, per k,
// whether active[k] reached its hit (always, in vacuum) with its weight
// kept.
template <typename State, typename AtCollision, typename OnScatter>
std::vector<uint8_t> WalkToHits(const SceneView& scene, const std::vector<uint32_t>& active,
                                const std::vector<Hit>& hits, State&& state, AtCollision&& at_collision,
                                OnScatter&& on_scatter) {
  std::vector<uint8_t> at_hit(active.size(), 1);
  std::vector<uint32_t> keys(active.size());
  for (size_t k = 0; k < active.size(); ++k) keys[k] = state(active[k]).medium;
  for (const auto& [medium, members] : GroupBy(keys)) {
    if (medium == kNoMedium) continue;
    std::vector<Walk> walks(members.size());
    for (size_t j = 0; j < members.size(); ++j) {
      const WalkState s = state(active[members[j]]);
      const Hit& hit = hits[members[j]];
      walks[j] = {s.ray, hit.Found() ? hit.t : s.ray.tfar, s.path.hero, &s.path.random};
    }
    std::vector<uint8_t> reached;
    const std::vector<Vec3> transmittance =
        TrackMajorants(scene.MediumAt(medium), walks, reached, [&](size_t j, const Collision& c) {
          const uint32_t i = active[members[j]];
          at_collision(i, c);
          const CollisionEvent event = DeltaTrack(state(i).path, c);
          if (event == CollisionEvent::kScatter) on_scatter(i, c);
          return event == CollisionEvent::kNull;
        });
    for (size_t j = 0; j < members.size(); ++j)
      at_hit[members[j]] = reached[j] && state(active[members[j]]).path.Pass(transmittance[j]);
  }
  return at_hit;
}

// A path's walk state, for paths that keep ray and medium beside their weight.
template <typename Path>
WalkState WalkStateOf(Path& path) {
  return {path.ray, path.medium, path};
}

// Whether any material of the scene is a null boundary.
inline bool HasNullBoundaries(const SceneView& scene) {
  for (uint32_t m = 0; m < scene.MaterialCount(); ++m)
    if (scene.Material(m).Lobes() & kScatterNull) return true;
  return false;
}

// Methods whose paths start only at the lights cannot start them in a
// medium that emits (pbrt-v4's Le): they refuse it.
inline void RefuseEmittingMedia(const SceneView& scene, const std::string& transport) {
  for (uint32_t m = 0; m < scene.MediumCount(); ++m)
    if (scene.MediumAt(m).Emits())
      throw Error(transport + " does not render media that emit light: render this scene with volpath");
}

inline bool IsNullBoundary(const SceneView& scene, uint32_t shape) {
  return (scene.Material(scene.MaterialOf(shape)).Lobes() & kScatterNull) != 0;
}

// The ray that goes on through the surface `hit` of `ray`, for what was
// left of its interval.
inline Ray Beyond(const Ray& ray, const Hit& hit) {
  Ray next = ray;
  Redirect(next, ray.origin + ray.direction * hit.t, hit.normal, ray.direction);
  next.tfar = ray.tfar < kInfinity ? std::max(0.0f, ray.tfar - hit.t) : kInfinity;
  return next;
}

// Where the camera ray of a point first met a surface: the ray's last leg
// and its hit, and where the camera ray started.
struct CameraHit {
  uint32_t point;
  Ray ray;
  Hit hit;
  Vec3 start;
};

// The first surface each camera ray meets, for the points whose ray meets
// one. With `through_boundaries`, null boundaries (interfaces of media)
// are not surfaces: the rays go on through them, one Intersect batch per
// crossing (at most 256, so that a degenerate stack of coincident
// boundaries cannot stall a batch).
inline std::vector<CameraHit> FirstCameraHits(const SceneView& scene, const PrimarySamples& points,
                                              bool through_boundaries) {
  constexpr int kMaxCrossings = 256;
  const size_t n = points.Count();
  std::vector<CameraHit> found;
  found.reserve(n);
  std::vector<Ray> rays(n);
  std::vector<uint32_t> active(n);
  for (uint32_t i = 0; i < n; ++i) {
    rays[i] = CameraRayOf(scene, points, i);
    active[i] = i;
  }
  for (int crossing = 0; !active.empty() && crossing <= kMaxCrossings; ++crossing) {
    std::vector<Ray> batch(active.size());
    std::vector<Hit> hits(active.size());
    for (size_t k = 0; k < active.size(); ++k) batch[k] = rays[active[k]];
    scene.Intersect(batch, hits);
    std::vector<uint32_t> next;
    for (size_t k = 0; k < active.size(); ++k) {
      if (!hits[k].Found()) continue;
      if (through_boundaries && IsNullBoundary(scene, hits[k].shape)) {
        rays[active[k]] = Beyond(batch[k], hits[k]);
        next.push_back(active[k]);
        continue;
      }
      found.push_back({active[k], batch[k], hits[k], CameraRayOf(scene, points, active[k]).origin});
    }
    active = std::move(next);
  }
  return found;
}

// A shadow ray that starts in `medium`, its hero channel and its random seed.
struct ShadowWalk {
  Ray ray;
  uint32_t medium = kNoMedium;
  uint32_t hero = 0;
  uint64_t seed = 0;
};

// Transmittance of a shadow ray (per channel) and the ratios of its
// channels' densities, to be multiplied into the path's.
struct ShadowTransmittance {
  Vec3 value{1, 1, 1}, r_u{1, 1, 1}, r_l{1, 1, 1};
};

// A collision on a shadow ray: its null part goes on (ratio tracking,
// with pbrt-v4's roulette once little is left). Returns whether it does.
inline bool RatioTrack(ShadowTransmittance& t, uint32_t hero, const Collision& c, WalkRandom& random) {
  const int h = int(hero);
  const Vec3 sigma_n = NonNegative(c.sigma_maj - c.sigma_a - c.sigma_s);
  const float pdf = c.transmittance_maj[h] * c.sigma_maj[h];
  t.value *= c.transmittance_maj * sigma_n / pdf;
  t.r_l *= c.transmittance_maj * c.sigma_maj / pdf;
  t.r_u *= c.transmittance_maj * sigma_n / pdf;
  const Vec3 estimate = t.value / ChannelMean(t.r_l + t.r_u);
  if (MaxComponent(estimate) < 0.05f) {
    if (random.Next() < 0.75f) {
      t.value = Vec3();
    } else {
      t.value *= 1 / 0.25f;
    }
  }
  return MaxComponent(t.value) > 0;
}

// The transmittance along each shadow ray, to its tfar: through media by
// ratio tracking, through null boundaries (changing medium as they say),
// zero at any other surface. Without media or null boundaries
// (`through_boundaries` false), one Occluded batch.
inline std::vector<ShadowTransmittance> Transmittances(const SceneView& scene, std::span<const ShadowWalk> shadows,
                                                       bool through_boundaries) {
  const size_t n = shadows.size();
  std::vector<ShadowTransmittance> out(n);
  std::vector<Ray> rays(n);
  for (size_t k = 0; k < n; ++k) rays[k] = shadows[k].ray;
  if (scene.MediumCount() == 0 && !through_boundaries) {
    std::vector<uint8_t> occluded(n);
    scene.Occluded(rays, occluded);
    for (size_t k = 0; k < n; ++k)
      if (occluded[k]) out[k].value = Vec3();
    return out;
  }
  std::vector<uint32_t> medium(n), active(n);
  std::vector<WalkRandom> random(n);
  for (uint32_t k = 0; k < n; ++k) {
    medium[k] = shadows[k].medium;
    random[k].seed = shadows[k].seed;
    active[k] = k;
  }
  while (!active.empty()) {
    std::vector<Ray> batch(active.size());
    std::vector<Hit> hits(active.size());
    for (size_t j = 0; j < active.size(); ++j) batch[j] = rays[active[j]];
    scene.Intersect(batch, hits);
    std::vector<uint32_t> keys(active.size());
    for (size_t j = 0; j < active.size(); ++j) {
      const bool blocked = hits[j].Found() && !IsNullBoundary(scene, hits[j].shape);
      if (blocked) out[active[j]].value = Vec3();
      keys[j] = blocked ? kNoMedium : medium[active[j]];
    }
    for (const auto& [medium_index, members] : GroupBy(keys)) {
      if (medium_index == kNoMedium) continue;
      std::vector<Walk> walks(members.size());
      for (size_t q = 0; q < members.size(); ++q) {
        const uint32_t k = active[members[q]];
        walks[q] = {rays[k], hits[members[q]].Found() ? hits[members[q]].t : rays[k].tfar, shadows[k].hero, &random[k]};
      }
      std::vector<uint8_t> reached;
      const std::vector<Vec3> transmittance =
          TrackMajorants(scene.MediumAt(medium_index), walks, reached, [&](size_t q, const Collision& c) {
            const uint32_t k = active[members[q]];
            return RatioTrack(out[k], shadows[k].hero, c, random[k]);
          });
      for (size_t q = 0; q < members.size(); ++q) {
        ShadowTransmittance& t = out[active[members[q]]];
        const float hero = transmittance[q][int(walks[q].hero)];
        if (!reached[q] || !(hero > 0)) {
          t.value = Vec3();
          continue;
        }
        t.value *= transmittance[q] / hero;
        t.r_u *= transmittance[q] / hero;
        t.r_l *= transmittance[q] / hero;
      }
    }
    // On through null boundaries, to the ray's end.
    std::vector<uint32_t> next;
    for (size_t j = 0; j < active.size(); ++j) {
      const uint32_t k = active[j];
      const Hit& hit = hits[j];
      if (!hit.Found() || !(MaxComponent(out[k].value) > 0)) continue;
      Ray& ray = rays[k];
      const Vec3 origin = OffsetRayOrigin(ray.origin + ray.direction * hit.t, hit.normal, ray.direction);
      const float left = ray.tfar - Dot(origin - ray.origin, ray.direction);
      if (!(left > 0)) continue;
      medium[k] = scene.MediaOf(hit.shape).Beyond(ray.direction, hit.normal, medium[k]);
      ray.origin = origin;
      ray.tfar = left;
      next.push_back(k);
    }
    active.swap(next);
  }
  return out;
}

// The medium each point lies in, found along the straight line to it from
// the camera (whose medium the scene names) through every boundary it
// crosses; kNoMedium for all when the scene has no media.
inline std::vector<uint32_t> MediaAt(const SceneView& scene, std::span<const Vec3> points, float time) {
  const size_t n = points.size();
  std::vector<uint32_t> medium(n, scene.CameraMedium());
  if (scene.MediumCount() == 0) return medium;
  const Vec3 eye = scene.CameraRay(0.5f, 0.5f, 0.5f, 0.5f, time).origin;
  std::vector<Ray> rays(n);
  std::vector<uint32_t> active;
  for (uint32_t k = 0; k < n; ++k) {
    const Vec3 d = points[k] - eye;
    const float length = Length(d);
    if (!(length > SurfaceOffset(points[k]))) continue;
    rays[k].origin = eye;
    rays[k].direction = d / length;
    rays[k].tfar = length - SurfaceOffset(points[k]);
    rays[k].time = time;
    active.push_back(k);
  }
  while (!active.empty()) {
    std::vector<Ray> batch(active.size());
    std::vector<Hit> hits(active.size());
    for (size_t j = 0; j < active.size(); ++j) batch[j] = rays[active[j]];
    scene.Intersect(batch, hits);
    std::vector<uint32_t> next;
    for (size_t j = 0; j < active.size(); ++j) {
      const uint32_t k = active[j];
      if (!hits[j].Found()) continue;
      Ray& ray = rays[k];
      medium[k] = scene.MediaOf(hits[j].shape).Beyond(ray.direction, hits[j].normal, medium[k]);
      const Vec3 origin = OffsetRayOrigin(ray.origin + ray.direction * hits[j].t, hits[j].normal, ray.direction);
      const float left = ray.tfar - Dot(origin - ray.origin, ray.direction);
      if (!(left > 0)) continue;
      ray.origin = origin;
      ray.tfar = left;
      next.push_back(k);
    }
    active.swap(next);
  }
  return medium;
}

// The medium each light path starts in: the one its light's point lies
// in, seen along the line from the camera, and on an emitting boundary
// the one it emits into.
inline std::vector<uint32_t> LightStartMedia(const SceneView& scene, const std::vector<LightStart>& starts,
                                             float time) {
  std::vector<uint32_t> media(starts.size(), kNoMedium);
  if (scene.MediumCount() == 0) return media;
  std::vector<Vec3> points(starts.size());
  for (size_t i = 0; i < starts.size(); ++i) points[i] = starts[i].light.position;
  media = MediaAt(scene, points, time);
  for (size_t i = 0; i < starts.size(); ++i) {
    const LightSample& l = starts[i].light;
    if (l.shape != kNoShape) media[i] = scene.MediaOf(l.shape).Beyond(starts[i].direction, l.normal, media[i]);
  }
  return media;
}

}  // namespace yarf
