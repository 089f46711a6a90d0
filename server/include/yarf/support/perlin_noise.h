// Perlin's gradient noise and its sums over octaves, as pbrt-v4 defines
// them (its solid textures' and its cloud medium's building blocks): the
// same permutation, the same 16 gradients and quintic fade, octaves 1.99
// times finer each.
//
// pbrt-v4's textures drop the octaves finer than a pixel's footprint (its
// ray differentials); yarf has no footprint in texture space, so every
// octave is summed: pbrt's value as that footprint vanishes. Pixels then
// average the fine octaves instead of dropping them, to the same mean.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "yarf/vecmath.h"

namespace yarf {

namespace perlin {

// Ken Perlin's permutation of 0–255 (his reference implementation's, and
// pbrt's), so that noise values match pbrt's at every point.
inline constexpr std::array<uint8_t, 256> kPermutation = {
    151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103, 30,  69,  142,
    8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,  0,   26,  197, 62,  94,  252, 219, 203,
    117, 35,  11,  32,  57,  177, 33,  88,  237, 149, 56,  87,  174, 20,  125, 136, 171, 168, 68,  175, 74,  165,
    71,  134, 139, 48,  27,  166, 77,  146, 158, 231, 83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,
    55,  46,  245, 40,  244, 102, 143, 54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187, 208, 89,
    18,  169, 200, 196, 135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250,
    124, 123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,  182, 189,
    28,  42,  223, 183, 170, 213, 119, 248, 152, 2,   44,  154, 163, 70,  221, 153, 101, 155, 167, 43,  172, 9,
    129, 22,  39,  253, 19,  98,  108, 110, 79,  113, 224, 232, 178, 185, 112, 104, 218, 246, 97,  228, 251, 34,
    242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,  51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,
    181, 199, 106, 157, 184, 84,  204, 176, 115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,  222, 114,
    67,  29,  24,  72,  243, 141, 128, 195, 78,  66,  215, 61,  156, 180};

inline int Permuted(int i) { return kPermutation[size_t(i & 255)]; }

// The gradient of lattice point (x, y, z), one of 12 edge directions of a
// cube (4 repeated), dotted with the offset (dx, dy, dz) from it.
inline float Gradient(int x, int y, int z, float dx, float dy, float dz) {
  const int h = Permuted(Permuted(Permuted(x) + y) + z) & 15;
  const float u = h < 8 || h == 12 || h == 13 ? dx : dy;
  const float v = h < 4 || h == 12 || h == 13 ? dy : dz;
  return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

// Perlin's quintic fade: C² joins between cells.
inline float Fade(float t) { return t * t * t * (t * (t * 6 - 15) + 10); }

inline float Lerp(float t, float a, float b) { return (1 - t) * a + t * b; }

}  // namespace perlin

// Noise at p: 0 at every lattice point, within about [−1, 1], period 256;
// 0 at a point not finite.
inline float Noise(Vec3 p) {
  if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) return 0;
  // Coordinates beyond 2³⁰ are brought back into range (the lattice
  // repeats every 256 cells) before they would overflow an int.
  const float x = std::fmod(p.x, float(1 << 30)), y = std::fmod(p.y, float(1 << 30)),
              z = std::fmod(p.z, float(1 << 30));
  const float fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const float dx = x - fx, dy = y - fy, dz = z - fz;
  const int ix = int(fx) & 255, iy = int(fy) & 255, iz = int(fz) & 255;
  using perlin::Gradient, perlin::Lerp;
  const float w000 = Gradient(ix, iy, iz, dx, dy, dz), w100 = Gradient(ix + 1, iy, iz, dx - 1, dy, dz);
  const float w010 = Gradient(ix, iy + 1, iz, dx, dy - 1, dz), w110 = Gradient(ix + 1, iy + 1, iz, dx - 1, dy - 1, dz);
  const float w001 = Gradient(ix, iy, iz + 1, dx, dy, dz - 1), w101 = Gradient(ix + 1, iy, iz + 1, dx - 1, dy, dz - 1);
  const float w011 = Gradient(ix, iy + 1, iz + 1, dx, dy - 1, dz - 1);
  const float w111 = Gradient(ix + 1, iy + 1, iz + 1, dx - 1, dy - 1, dz - 1);
  const float wx = perlin::Fade(dx), wy = perlin::Fade(dy), wz = perlin::Fade(dz);
  const float y0 = Lerp(wy, Lerp(wx, w000, w100), Lerp(wx, w010, w110));
  const float y1 = Lerp(wy, Lerp(wx, w001, w101), Lerp(wx, w011, w111));
  return Lerp(wz, y0, y1);
}

// The noise's gradient by forward differences of 0.01 (pbrt's DNoise).
inline Vec3 NoiseGradient(Vec3 p) {
  constexpr float kDelta = 0.01f;
  const float n = Noise(p);
  return Vec3(Noise(p + Vec3(kDelta, 0, 0)) - n, Noise(p + Vec3(0, kDelta, 0)) - n, Noise(p + Vec3(0, 0, kDelta)) - n) /
         kDelta;
}

// Fractional Brownian motion: Σ ωⁱ Noise(1.99ⁱ p) over `octaves` octaves.
inline float FBm(Vec3 p, float omega, int octaves) {
  float sum = 0, lambda = 1, weight = 1;
  for (int i = 0; i < octaves; ++i) {
    sum += weight * Noise(p * lambda);
    lambda *= 1.99f;
    weight *= omega;
  }
  return sum;
}

// Turbulence: Σ ωⁱ |Noise(1.99ⁱ p)|, plus pbrt-v4's 0.2 ω^octaves for the
// octaves beyond (the mean of |Noise| it stands in for them).
inline float Turbulence(Vec3 p, float omega, int octaves) {
  float sum = 0, lambda = 1, weight = 1;
  for (int i = 0; i < octaves; ++i) {
    sum += weight * std::abs(Noise(p * lambda));
    lambda *= 1.99f;
    weight *= omega;
  }
  return sum + weight * 0.2f;
}

}  // namespace yarf
