// Null-scattering tracking through a medium (Miller, Georgiev & Jarosz
// 2019, as pbrt-v4's SampleT_maj): tentative collisions along a ray are
// drawn with the majorant σ_maj of one channel (the hero), and the caller
// decides at each one whether it absorbs, scatters or is null — delta
// tracking for paths, ratio tracking for shadow rays. Batched: every
// round gathers one tentative collision of each unfinished walk and asks
// the medium for its coefficients in one call.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "yarf/error.h"
#include "yarf/geometry.h"
#include "yarf/support/hash.h"
#include "yarf/medium.h"

namespace yarf {

// The random numbers of one walk: a hash of its seed and a counter, so
// that walks of any length need no primary-sample dimensions.
struct WalkRandom {
  uint64_t seed = 0;
  uint32_t count = 0;
  float Next() { return ToUnitFloat(uint32_t(Hash(seed, count++))); }
};

// exp(-σ·length) per channel; a channel with σ = 0 keeps all its light
// even over an infinite length.
inline Vec3 MajorantTransmittance(Vec3 sigma, float length) {
  const auto channel = [&](float s) { return s > 0 ? std::exp(-s * length) : 1.0f; };
  return {channel(sigma.x), channel(sigma.y), channel(sigma.z)};
}

// The mean of the three channels: pbrt-v4's average over wavelengths of
// rescaled path densities, the balance heuristic over hero channels.
inline float ChannelMean(Vec3 v) { return (v.x + v.y + v.z) / 3; }

// What a walk meets at a tentative collision.
struct Collision {
  Vec3 position;
  float t = 0;
  Vec3 sigma_a, sigma_s, emission;
  Vec3 sigma_maj;
  // exp(-σ_maj·Δt) from the previous collision (or the ray's start).
  Vec3 transmittance_maj;
};

// More tentative collisions than this along one walk means a majorant
// absurdly far above the medium (or a medium absurdly thick for the
// scene's size): the job fails rather than walk for ever.
inline constexpr uint32_t kMaxCollisionsPerWalk = 1u << 20;

// One walk: a ray through the medium over [0, tmax), the channel whose
// majorant draws the collisions, and its random numbers.
struct Walk {
  Ray ray;
  float tmax = 0;
  uint32_t hero = 0;
  WalkRandom* random = nullptr;
};

// Walks every ray through `medium`. At each tentative collision,
// on_collision(walk index, collision) returns whether the walk goes on.
// Returns, per walk, exp(-σ_maj·Δt) from its last collision to tmax for
// walks that reached it, and zero for walks that stopped at a collision;
// `reached` says which.
template <typename OnCollision>
std::vector<Vec3> TrackMajorants(const Medium& medium, std::span<const Walk> walks, std::vector<uint8_t>& reached,
                                 OnCollision&& on_collision) {
  const size_t n = walks.size();
  std::vector<Vec3> transmittance(n, Vec3(1, 1, 1));
  reached.assign(n, 0);
  if (n == 0) return transmittance;
  std::vector<float> origin(3 * n), direction(3 * n), tmax(n);
  for (size_t i = 0; i < n; ++i) {
    walks[i].ray.origin.Store(&origin[3 * i]);
    walks[i].ray.direction.Store(&direction[3 * i]);
    tmax[i] = walks[i].tmax;
  }
  MajorantSegments majorants;
  medium.Majorants(origin, direction, tmax, majorants);

  // Where each walk is: its segment and its t within it.
  std::vector<uint32_t> segment(n), collisions(n);
  std::vector<float> t(n);
  std::vector<uint32_t> active;
  for (uint32_t i = 0; i < n; ++i) {
    segment[i] = majorants.offsets[i];
    t[i] = 0;
    active.push_back(i);
  }
  std::vector<uint32_t> colliding, next;
  std::vector<float> position, sigma_a, sigma_s, emission;
  while (!active.empty()) {
    // Each walk moves to its next tentative collision or to its end.
    colliding.clear();
    for (uint32_t i : active) {
      const Walk& walk = walks[i];
      const uint32_t end = majorants.offsets[i + 1];
      bool collides = false;
      while (segment[i] < end) {
        const MajorantSegment& s = majorants.segments[segment[i]];
        const float t1 = std::min(s.t1, walk.tmax);
        t[i] = std::max(t[i], s.t0);
        const float sigma = s.sigma_maj[walk.hero];
        if (t[i] < t1 && sigma > 0) {
          const float step = -std::log1p(-walk.random->Next()) / sigma;
          if (t[i] + step < t1) {
            transmittance[i] *= MajorantTransmittance(s.sigma_maj, step);
            t[i] += step;
            collides = true;
            if (++collisions[i] > kMaxCollisionsPerWalk)
              throw Error("a ray met more than " + std::to_string(kMaxCollisionsPerWalk) +
                          " collisions in one medium: its majorant (" + std::to_string(sigma) +
                          " per unit length) is far too large for the scene");
            break;
          }
        }
        if (t[i] < t1) transmittance[i] *= MajorantTransmittance(s.sigma_maj, t1 - t[i]);
        t[i] = t1;
        ++segment[i];
      }
      if (collides) {
        colliding.push_back(i);
      } else {
        reached[i] = 1;
      }
    }
    if (colliding.empty()) break;
    const size_t m = colliding.size();
    position.resize(3 * m);
    sigma_a.resize(3 * m);
    sigma_s.resize(3 * m);
    emission.resize(3 * m);
    for (size_t k = 0; k < m; ++k) {
      const Ray& ray = walks[colliding[k]].ray;
      (ray.origin + ray.direction * t[colliding[k]]).Store(&position[3 * k]);
    }
    medium.Coefficients(position, sigma_a, sigma_s, emission);
    next.clear();
    for (size_t k = 0; k < m; ++k) {
      const uint32_t i = colliding[k];
      Collision c{Vec3::Load(&position[3 * k]), t[i], Vec3::Load(&sigma_a[3 * k]), Vec3::Load(&sigma_s[3 * k]),
                  Vec3::Load(&emission[3 * k]), majorants.segments[segment[i]].sigma_maj, transmittance[i]};
      transmittance[i] = Vec3(1, 1, 1);
      if (on_collision(i, c)) {
        next.push_back(i);
      } else {
        transmittance[i] = Vec3();
      }
    }
    active.swap(next);
  }
  return transmittance;
}

}  // namespace yarf
