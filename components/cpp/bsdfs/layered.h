// The stochastic layered model of pbrt-v4's LayeredBxDF, which
// coateddiffuse.cc and coatedconductor.cc share: a dielectric interface
// on top (smooth, or GGX-rough), an opaque bottom layer (diffuse, or a
// conductor) and between them, optionally, a homogeneous slab of
// thickness `thickness` (in units of its mean free path: σt = 1), single-
// scattering albedo `albedo` and Henyey–Greenstein phase function of
// asymmetry g. Light is followed by a random walk between the two
// interfaces (Guo, Hašan, Yan & Zhao, "Position-free Monte Carlo
// simulation for arbitrary layered BSDFs", SIGGRAPH Asia 2018), as pbrt-v4
// does it (Pharr, Jakob & Humphreys, PBR 4th ed., §14.3):
//
//   Value    an unbiased estimate of f(v, l): the top's reflection plus
//            `samples` walks started by refracting both v and l into the
//            slab, joined at each bounce by next-event estimation with
//            MIS (power heuristic) between the two ends;
//   Sample   a walk from v that ends when it leaves through the top: its
//            throughput is an unbiased estimate of f·|cos|/p(l), p the
//            walk's (unknown) density of l;
//   Density  pbrt's stochastic estimate of that density (the top's
//            reflection, and the TRT paths through one bottom bounce),
//            mixed 9:1 with the uniform hemisphere so that it is > 0
//            wherever a walk can leave.
//
// One correction to pbrt: where a walk's step through the top toward l
// and the join drawn from l (the "virtual light") could both produce a
// direction inside the slab, the power heuristic here weighs them by the
// densities of those two techniques at that one direction (the join's:
// the top's transmission density from l to it); pbrt weighs the step by
// the density of l from it instead, so its two weights do not sum to 1 and
// its estimate of f is biased under a rough coat (measured here: 7% too
// bright for a white base under roughness 0.05).
//
// The numbers a walk needs come from Rng, a counter over a hash of the
// call's inputs, so each call is a deterministic function of them (pbrt
// seeds its RNG from a hash of the directions); the estimates are unbiased
// over the hash's randomness.
//
// Directions here follow pbrt's names for what a BxDF is given and what
// it draws: `v` is the direction given (pbrt's wo, yarf's wi: toward the
// camera for radiance), `l` the other one (pbrt's wi, yarf's wo). Both
// sides scatter alike (pbrt's coated materials are two-sided): v below the
// surface is handled by mirroring both directions.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "microfacet.h"
#include "yarf/support/scatter_rows.h"
#include "yarf/error.h"
#include "yarf/support/hash.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/surface.h"
#include "yarf/surface_points.h"
#include "yarf/texture.h"
#include "yarf/vecmath.h"
#include "yarf/support/warps.h"

namespace yarf::layered {

namespace mf = yarf::microfacet;

// pbrt's threshold below which a GGX roughness is a mirror.
inline constexpr float kSmoothAlpha = 1e-3f;

// --- Random numbers -----------------------------------------------------------

inline uint64_t Bits(float x) { return std::bit_cast<uint32_t>(x); }

// A stream of uniform numbers in [0, 1) from a seed: number n is a hash of
// (seed, n).
class Rng {
 public:
  explicit Rng(uint64_t seed) : seed_(seed) {}
  float operator()() { return ToUnitFloat(uint32_t(Hash(seed_, count_++) >> 32)); }

 private:
  uint64_t seed_, count_ = 0;
};

// A seed from a salt (which call), two directions and the uv of row k
// (0 when the call has none).
inline uint64_t Seed(uint64_t salt, Vec3 a, Vec3 b, const SurfacePoints& at, size_t k) {
  const bool has_uv = at.uv.size() >= 2 * k + 2;
  const float u = has_uv ? at.uv[2 * k] : 0.0f, v = has_uv ? at.uv[2 * k + 1] : 0.0f;
  return Hash(salt, Bits(a.x), Bits(a.y), Bits(a.z), Bits(b.x), Bits(b.y), Bits(b.z), Bits(u), Bits(v));
}

// --- What one interface draws -------------------------------------------------

enum Sides : uint32_t { kReflection = 1, kTransmission = 2, kBothSides = 3 };

// A drawn direction: its value f (no cosine), density (solid angle, or a
// discrete probability when `specular`) and side.
struct Scatter {
  Vec3 f, w;
  float pdf = 0;
  bool specular = false, transmit = false;
  bool Ok() const { return pdf > 0 && w.z != 0 && (f.x > 0 || f.y > 0 || f.z > 0); }
};

inline Vec3 Grey(float x) { return {x, x, x}; }
inline float PowerHeuristic(float f, float g) {
  if (std::isinf(f * f)) return 1.0f;
  const float sum = f * f + g * g;
  return sum > 0 ? f * f / sum : 0.0f;
}

// The density of normals visible from w (either side), pbrt's D_w(m).
inline float VisibleDensity(Vec3 w, Vec3 m, const mf::Roughness& r) {
  if (w.z == 0) return 0.0f;
  return mf::SmithG1(w, r) / std::abs(w.z) * mf::Ndf(m, r) * std::abs(Dot(w, m));
}

inline Vec3 SampleVisible(Vec3 w, const mf::Roughness& r, float u0, float u1) {
  return mf::SampleVisibleNormal(w.z >= 0 ? w : -w, r, u0, u1);
}

inline bool IsSmooth(const mf::Roughness& r) { return std::max(r.alpha_x, r.alpha_y) < kSmoothAlpha; }

// --- The interfaces -----------------------------------------------------------

// The top: a dielectric of relative index eta (below over above), smooth
// or GGX-rough, reflecting and transmitting (pbrt's DielectricBxDF).
struct Dielectric {
  float eta = 1.5f;
  mf::Roughness alpha;

  bool Smooth() const { return eta == 1.0f || IsSmooth(alpha); }

  // The generalised half vector of (v, l), facing +z; false when there is
  // none or it faces away from either direction.
  bool HalfVector(Vec3 v, Vec3 l, Vec3* m, float* etap) const {
    if (v.z == 0 || l.z == 0) return false;
    *etap = v.z * l.z > 0 ? 1.0f : (v.z > 0 ? eta : 1.0f / eta);
    Vec3 h = l * *etap + v;
    const float length2 = Dot(h, h);
    if (!(length2 > 0)) return false;
    h = h / std::sqrt(length2);
    if (h.z < 0) h = -h;
    if (Dot(h, l) * l.z < 0 || Dot(h, v) * v.z < 0) return false;
    *m = h;
    return true;
  }

  Vec3 F(Vec3 v, Vec3 l, TransportMode mode) const {
    Vec3 m;
    float etap;
    if (Smooth() || !HalfVector(v, l, &m, &etap)) return {};
    const float fresnel = FresnelDielectric(Dot(v, m), eta);
    const float dg = mf::Ndf(m, alpha) * mf::SmithG2(v, l, alpha);
    if (v.z * l.z > 0) return Grey(dg * fresnel / std::abs(4.0f * v.z * l.z));
    const float root = Dot(l, m) + Dot(v, m) / etap;
    float ft = dg * (1.0f - fresnel) * std::abs(Dot(l, m) * Dot(v, m) / (root * root * l.z * v.z));
    if (mode == TransportMode::kRadiance) ft /= etap * etap;
    return Grey(ft);
  }

  Scatter Sample(Vec3 v, float uc, float u0, float u1, TransportMode mode, uint32_t sides) const {
    Scatter s;
    if (Smooth()) {
      const float r = FresnelDielectric(v.z, eta), t = 1.0f - r;
      const float pr = sides & kReflection ? r : 0.0f, pt = sides & kTransmission ? t : 0.0f;
      if (!(pr + pt > 0)) return s;
      s.specular = true;
      if (uc < pr / (pr + pt)) {
        s.w = {-v.x, -v.y, v.z};
        s.f = Grey(r / std::abs(v.z));
        s.pdf = pr / (pr + pt);
        return s;
      }
      if (!Refract(v, eta, &s.w)) return {};
      const float etap = v.z > 0 ? eta : 1.0f / eta;
      float ft = t / std::abs(s.w.z);
      if (mode == TransportMode::kRadiance) ft /= etap * etap;
      s.f = Grey(ft);
      s.pdf = pt / (pr + pt);
      s.transmit = true;
      return s;
    }
    if (v.z == 0) return s;
    const Vec3 m = SampleVisible(v, alpha, u0, u1);
    const float r = FresnelDielectric(Dot(v, m), eta), t = 1.0f - r;
    const float pr = sides & kReflection ? r : 0.0f, pt = sides & kTransmission ? t : 0.0f;
    if (!(pr + pt > 0)) return s;
    const float visible = VisibleDensity(v, m, alpha);
    if (uc < pr / (pr + pt)) {
      s.w = mf::ReflectAbout(v, m);
      if (!(s.w.z * v.z > 0)) return {};
      s.pdf = visible / (4.0f * std::abs(Dot(v, m))) * pr / (pr + pt);
      s.f = Grey(mf::Ndf(m, alpha) * mf::SmithG2(v, s.w, alpha) * r / std::abs(4.0f * s.w.z * v.z));
      return s;
    }
    if (!mf::RefractAbout(v, m, eta, &s.w) || !(s.w.z * v.z < 0)) return {};
    const float etap = Dot(v, m) > 0 ? eta : 1.0f / eta;
    const float root = Dot(s.w, m) + Dot(v, m) / etap;
    s.pdf = visible * std::abs(Dot(s.w, m)) / (root * root) * pt / (pr + pt);
    float ft = t * mf::Ndf(m, alpha) * mf::SmithG2(v, s.w, alpha) *
               std::abs(Dot(s.w, m) * Dot(v, m) / (s.w.z * v.z * root * root));
    if (mode == TransportMode::kRadiance) ft /= etap * etap;
    s.f = Grey(ft);
    s.transmit = true;
    return s;
  }

  float Pdf(Vec3 v, Vec3 l, uint32_t sides) const {
    Vec3 m;
    float etap;
    if (Smooth() || !HalfVector(v, l, &m, &etap)) return 0.0f;
    const float r = FresnelDielectric(Dot(v, m), eta), t = 1.0f - r;
    const float pr = sides & kReflection ? r : 0.0f, pt = sides & kTransmission ? t : 0.0f;
    if (!(pr + pt > 0)) return 0.0f;
    const float visible = VisibleDensity(v, m, alpha);
    if (v.z * l.z > 0) return visible / (4.0f * std::abs(Dot(v, m))) * pr / (pr + pt);
    const float root = Dot(l, m) + Dot(v, m) / etap;
    return visible * std::abs(Dot(l, m)) / (root * root) * pt / (pr + pt);
  }
};

// A diffuse bottom of reflectance R (pbrt's DiffuseBxDF).
struct Diffuse {
  static constexpr bool kDiffuse = true;
  Vec3 reflectance;

  bool Smooth() const { return false; }
  Vec3 F(Vec3 v, Vec3 l, TransportMode) const { return v.z * l.z > 0 ? reflectance * kInvPi : Vec3(); }
  Scatter Sample(Vec3 v, float, float u0, float u1, TransportMode, uint32_t sides) const {
    Scatter s;
    if (!(sides & kReflection)) return s;
    s.w = SampleCosineHemisphere(u0, u1);
    if (v.z < 0) s.w.z = -s.w.z;
    s.pdf = CosineHemispherePdf(std::abs(s.w.z));
    s.f = reflectance * kInvPi;
    return s;
  }
  float Pdf(Vec3 v, Vec3 l, uint32_t sides) const {
    return (sides & kReflection) && v.z * l.z > 0 ? CosineHemispherePdf(std::abs(l.z)) : 0.0f;
  }
};

// A conductor bottom of complex index eta + i k (relative to the slab),
// smooth or GGX-rough (pbrt's ConductorBxDF).
struct Conductor {
  static constexpr bool kDiffuse = false;
  mf::Roughness alpha;
  Vec3 eta, k;

  bool Smooth() const { return IsSmooth(alpha); }
  Vec3 F(Vec3 v, Vec3 l, TransportMode) const {
    if (!(v.z * l.z > 0) || Smooth()) return {};
    const Vec3 m = Normalize(v + l);
    const Vec3 fresnel = mf::FresnelConductor(std::abs(Dot(v, m)), eta, k);
    return fresnel * (mf::Ndf(m.z < 0 ? -m : m, alpha) * mf::SmithG2(v, l, alpha) / std::abs(4.0f * v.z * l.z));
  }
  Scatter Sample(Vec3 v, float, float u0, float u1, TransportMode, uint32_t sides) const {
    Scatter s;
    if (!(sides & kReflection) || v.z == 0) return s;
    if (Smooth()) {
      s.w = {-v.x, -v.y, v.z};
      s.f = mf::FresnelConductor(std::abs(v.z), eta, k) / std::abs(v.z);
      s.pdf = 1.0f;
      s.specular = true;
      return s;
    }
    const Vec3 m = SampleVisible(v, alpha, u0, u1);
    s.w = mf::ReflectAbout(v, m);
    if (!(s.w.z * v.z > 0)) return {};
    s.pdf = VisibleDensity(v, m, alpha) / (4.0f * std::abs(Dot(v, m)));
    s.f = mf::FresnelConductor(std::abs(Dot(v, m)), eta, k) *
          (mf::Ndf(m, alpha) * mf::SmithG2(v, s.w, alpha) / std::abs(4.0f * v.z * s.w.z));
    return s;
  }
  float Pdf(Vec3 v, Vec3 l, uint32_t sides) const {
    if (!(sides & kReflection) || !(v.z * l.z > 0) || Smooth()) return 0.0f;
    Vec3 m = Normalize(v + l);
    if (m.z < 0) m = -m;
    return VisibleDensity(v, m, alpha) / (4.0f * std::abs(Dot(v, m)));
  }
};

// --- The medium ---------------------------------------------------------------

// Henyey–Greenstein's phase function of asymmetry g for directions a, b
// that both point away from the scattering point (so forward scattering,
// g > 0, favours b ≈ -a), as pbrt's HGPhaseFunction.
inline float HenyeyGreenstein(float cos_ab, float g) {
  const float denominator = 1.0f + g * g + 2.0f * g * cos_ab;
  return (1.0f - g * g) / (4.0f * kPi * denominator * std::sqrt(std::max(denominator, 1e-12f)));
}

// Draws b given a with density HenyeyGreenstein(a·b, g) by inverting the
// CDF of the scattering cosine.
inline Vec3 SampleHenyeyGreenstein(Vec3 a, float g, float u0, float u1, float* pdf) {
  float cos_ab;
  if (std::abs(g) < 1e-3f) {
    cos_ab = 1.0f - 2.0f * u0;
  } else {
    // The cosine to the direction of travel (-a), then to a.
    const float q = (1.0f - g * g) / (1.0f + g - 2.0f * g * u0);
    cos_ab = -(1.0f + g * g - q * q) / (2.0f * g);
  }
  cos_ab = std::clamp(cos_ab, -1.0f, 1.0f);
  *pdf = HenyeyGreenstein(cos_ab, g);
  return Frame(a).ToWorld(SphericalDirection(SinFromCos(cos_ab), cos_ab, 2.0f * kPi * u1));
}

// The slab's transmittance over a height dz along w (σt = 1).
inline float Transmittance(float dz, Vec3 w) {
  if (std::abs(dz) <= std::numeric_limits<float>::min()) return 1.0f;
  return std::exp(-std::abs(dz / w.z));
}

// --- The layered model at one point --------------------------------------------

inline bool IsBlack(Vec3 c) { return !(c.x > 0 || c.y > 0 || c.z > 0); }

template <typename Bottom>
struct Layers {
  Dielectric top;
  Bottom bottom;
  float thickness = 0.01f;
  Vec3 albedo;
  float g = 0;
  int max_depth = 10, samples = 1;

  bool HasMedium() const { return !IsBlack(albedo); }
  // The kind of what the walk returns, as pbrt's LayeredBxDF::Flags.
  uint32_t WalkKind() const {
    return Bottom::kDiffuse || HasMedium() ? kScatterDiffuse : kScatterGlossy;
  }
  // Only delta paths: no finite value or density anywhere.
  bool OnlyDelta() const { return top.Smooth() && bottom.Smooth() && !HasMedium(); }
  float Thickness() const { return std::max(thickness, std::numeric_limits<float>::min()); }

  // An unbiased estimate of f(v, l), pbrt's LayeredBxDF::f for a
  // two-sided model with an opaque bottom.
  Vec3 Value(Vec3 v, Vec3 l, TransportMode mode, Rng& r) const {
    if (v.z < 0) v = -v, l = -l;
    if (!(l.z > 0) || !(v.z > 0) || OnlyDelta()) return {};
    const float depth_z = Thickness();
    const TransportMode adjoint =
        mode == TransportMode::kRadiance ? TransportMode::kImportance : TransportMode::kRadiance;
    Vec3 f = top.F(v, l, mode) * float(samples);
    for (int s = 0; s < samples; ++s) {
      // Into the slab from v, and (the adjoint way) from l.
      const float uc0 = r(), u00 = r(), u01 = r();
      const Scatter into = top.Sample(v, uc0, u00, u01, mode, kTransmission);
      const float uc1 = r(), u10 = r(), u11 = r();
      const Scatter from_l = top.Sample(l, uc1, u10, u11, adjoint, kTransmission);
      if (!into.Ok() || !from_l.Ok()) continue;
      Vec3 beta = into.f * (std::abs(into.w.z) / into.pdf);
      float z = depth_z;
      Vec3 w = into.w;
      for (int depth = 0; depth < max_depth; ++depth) {
        // A join leaves through the top at the next event, which Sample's
        // walk must still reach: the last event joins nothing, so that
        // Value and Sample truncate the same series (pbrt's f adds one
        // more order than its Sample_f draws).
        const bool joins = depth + 1 < max_depth;
        if (depth > 3 && MaxComponent(beta) < 0.25f) {
          const float q = std::max(0.0f, 1.0f - MaxComponent(beta));
          if (r() < q) break;
          beta = beta / (1.0f - q);
        }
        if (!HasMedium()) {
          z = z == depth_z ? 0.0f : depth_z;
          beta = beta * Transmittance(depth_z, w);
        } else {
          const float dz = -std::log1p(-r()) * std::abs(w.z);
          const float zp = w.z > 0 ? z + dz : z - dz;
          if (zp == z) continue;
          if (0 < zp && zp < depth_z) {
            // Scattered in the slab: join to l through the top, then
            // draw the phase function.
            float weight = 1;
            const float phase_l = HenyeyGreenstein(Dot(-w, -from_l.w), g);
            if (!top.Smooth()) weight = PowerHeuristic(from_l.pdf, phase_l);
            if (joins)
              f += beta * albedo * from_l.f * (phase_l * weight * Transmittance(zp - depth_z, from_l.w) / from_l.pdf);
            float phase_pdf = 0;
            const float p0 = r(), p1 = r();
            const Vec3 next = SampleHenyeyGreenstein(-w, g, p0, p1, &phase_pdf);
            if (!(phase_pdf > 0) || next.z == 0) continue;
            beta = beta * albedo;  // p / pdf = 1
            w = next;
            z = zp;
            if (joins && w.z > 0 && !top.Smooth()) {
              const Vec3 exit = top.F(-w, l, mode);
              if (!IsBlack(exit)) {
                // The density with which the join from l would draw -w.
                const float exit_pdf = top.Pdf(l, -w, kTransmission);
                f += beta * exit * (Transmittance(zp - depth_z, w) * PowerHeuristic(phase_pdf, exit_pdf));
              }
            }
            continue;
          }
          z = std::clamp(zp, 0.0f, depth_z);
        }
        if (z == depth_z) {
          // Reflected back down by the top, from inside.
          const float uc = r(), u0 = r(), u1 = r();
          const Scatter bs = top.Sample(-w, uc, u0, u1, mode, kReflection);
          if (!bs.Ok()) break;
          beta = beta * bs.f * (std::abs(bs.w.z) / bs.pdf);
          w = bs.w;
          continue;
        }
        // At the bottom: join to l through the top, then draw the bottom.
        if (joins && !bottom.Smooth()) {
          float weight = 1;
          if (!top.Smooth()) weight = PowerHeuristic(from_l.pdf, bottom.Pdf(-w, -from_l.w, kBothSides));
          f += beta * bottom.F(-w, -from_l.w, mode) * from_l.f *
               (std::abs(from_l.w.z) * weight * Transmittance(depth_z, from_l.w) / from_l.pdf);
        }
        const float uc = r(), u0 = r(), u1 = r();
        const Scatter bs = bottom.Sample(-w, uc, u0, u1, mode, kReflection);
        if (!bs.Ok()) break;
        beta = beta * bs.f * (std::abs(bs.w.z) / bs.pdf);
        w = bs.w;
        if (joins && !top.Smooth()) {
          const Vec3 exit = top.F(-w, l, mode);
          if (!IsBlack(exit)) {
            float weight = 1;
            if (!bottom.Smooth()) weight = PowerHeuristic(bs.pdf, top.Pdf(l, -w, kTransmission));
            f += beta * exit * (Transmittance(depth_z, bs.w) * weight);
          }
        }
      }
    }
    return f / float(samples);
  }

  // What Sample draws: l, the walk's f·|cos θl| / (its path density) as
  // `weight`, whether every event was a delta one (then `pdf` is the
  // path's discrete probability), and whether l is the top's own
  // reflection.
  struct Drawn {
    Vec3 l, weight;
    float pdf = 0;
    bool delta = false, top_reflection = false;
  };

  // pbrt's LayeredBxDF::Sample_f: a walk from v until it leaves through the
  // top (false when it dies).
  bool Sample(Vec3 v, float uc, float u0, float u1, TransportMode mode, Rng& r, Drawn* out) const {
    const bool flip = v.z < 0;
    if (flip) v = -v;
    if (!(v.z > 0)) return false;
    const float depth_z = Thickness();
    const Scatter first = top.Sample(v, uc, u0, u1, mode, kBothSides);
    if (!first.Ok()) return false;
    if (!first.transmit) {
      *out = {flip ? -first.w : first.w, first.f * (std::abs(first.w.z) / first.pdf), first.pdf, first.specular, true};
      return true;
    }
    Vec3 w = first.w;
    bool specular = first.specular;
    Vec3 f = first.f * std::abs(first.w.z);
    float pdf = first.pdf;
    float z = depth_z;
    for (int depth = 0; depth < max_depth; ++depth) {
      const float rr = MaxComponent(f) / pdf;
      if (depth > 3 && rr < 0.25f) {
        const float q = std::max(0.0f, 1.0f - rr);
        if (r() < q) return false;
        pdf *= 1.0f - q;
      }
      if (w.z == 0) return false;
      if (HasMedium()) {
        const float dz = -std::log1p(-r()) * std::abs(w.z);
        const float zp = w.z > 0 ? z + dz : z - dz;
        if (zp == z) return false;
        if (0 < zp && zp < depth_z) {
          float phase_pdf = 0;
          const float p0 = r(), p1 = r();
          const Vec3 next = SampleHenyeyGreenstein(-w, g, p0, p1, &phase_pdf);
          if (!(phase_pdf > 0) || next.z == 0) return false;
          f = f * albedo * phase_pdf;
          pdf *= phase_pdf;
          specular = false;
          w = next;
          z = zp;
          continue;
        }
        z = std::clamp(zp, 0.0f, depth_z);
      } else {
        z = z == depth_z ? 0.0f : depth_z;
        f = f * Transmittance(depth_z, w);
      }
      const float c = r(), s0 = r(), s1 = r();
      const Scatter bs = z == 0 ? bottom.Sample(-w, c, s0, s1, mode, kBothSides)
                                : top.Sample(-w, c, s0, s1, mode, kBothSides);
      if (!bs.Ok()) return false;
      f = f * bs.f;
      pdf *= bs.pdf;
      specular = specular && bs.specular;
      w = bs.w;
      if (bs.transmit) {
        if (!(w.z > 0)) return false;
        *out = {flip ? -w : w, f * (std::abs(w.z) / pdf), pdf, specular, false};
        return true;
      }
      f = f * std::abs(bs.w.z);
    }
    return false;
  }

  // pbrt's LayeredBxDF::PDF: a stochastic estimate of the density of the
  // non-delta part of Sample, mixed 9:1 with the uniform hemisphere on v's
  // side (pbrt: with the uniform sphere; here the model only reflects).
  float Density(Vec3 v, Vec3 l, TransportMode mode, Rng& r) const {
    if (v.z < 0) v = -v, l = -l;
    if (!(l.z > 0) || !(v.z > 0) || OnlyDelta()) return 0.0f;
    const TransportMode adjoint =
        mode == TransportMode::kRadiance ? TransportMode::kImportance : TransportMode::kRadiance;
    float sum = float(samples) * top.Pdf(v, l, kReflection);
    for (int s = 0; s < samples; ++s) {
      const float a0 = r(), a1 = r(), a2 = r();
      const Scatter into = top.Sample(v, a0, a1, a2, mode, kTransmission);
      const float b0 = r(), b1 = r(), b2 = r();
      const Scatter from_l = top.Sample(l, b0, b1, b2, adjoint, kTransmission);
      if (!into.Ok() || !from_l.Ok()) continue;
      if (top.Smooth()) {
        sum += bottom.Pdf(-into.w, -from_l.w, kBothSides);
        continue;
      }
      const float c0 = r(), c1 = r(), c2 = r();
      const Scatter rs = bottom.Sample(-into.w, c0, c1, c2, mode, kBothSides);
      if (!rs.Ok()) continue;
      if (bottom.Smooth()) {
        sum += top.Pdf(-rs.w, l, kBothSides);
        continue;
      }
      const float bottom_pdf = bottom.Pdf(-into.w, -from_l.w, kBothSides);
      sum += PowerHeuristic(from_l.pdf, bottom_pdf) * bottom_pdf;
      const float top_pdf = top.Pdf(-rs.w, l, kBothSides);
      sum += PowerHeuristic(rs.pdf, top_pdf) * top_pdf;
    }
    return 0.1f * UniformHemispherePdf(l.z) + 0.9f * sum / float(samples);
  }
};

// --- Reading the parameters ------------------------------------------------------

// pbrt's roughness parameters (`prefix`roughness, uroughness, vroughness;
// each a number ≥ 0 or a texture) and remaproughness: α = √roughness
// when remapped (pbrt's RoughnessToAlpha), else the roughness itself.
struct PbrtRoughness {
  TexturedValue u, v;
  bool remap = true;

  // The roughness at points of a call.
  struct Points {
    PointValues<float> u, v;
    bool remap;
    mf::Roughness operator[](size_t k) const {
      float au = u[k], av = v[k];
      if (remap) au = std::sqrt(std::max(au, 0.0f)), av = std::sqrt(std::max(av, 0.0f));
      // A rough GGX needs α > 0 along both axes.
      if (std::max(au, av) >= kSmoothAlpha) au = std::max(au, mf::kMinAlpha), av = std::max(av, mf::kMinAlpha);
      return {au, av, mf::Distribution::kGgx};
    }
  };
  Points At(const SurfacePoints& at) const { return {u.FloatsAt(at), v.FloatsAt(at), remap}; }

  // Whether it may be smooth, or rough, somewhere (a texture: both).
  bool MaySmooth() const { return !u.IsConstant() || !v.IsConstant() || IsSmooth(Constant()); }
  bool MayRough() const { return !u.IsConstant() || !v.IsConstant() || !IsSmooth(Constant()); }
  mf::Roughness Constant() const {
    return Points{PointValues<float>(u.Constant().x), PointValues<float>(v.Constant().x), remap}[0];
  }
};

inline TexturedValue ReadNonNegative(const Properties& props, const std::string& key, float fallback) {
  if (auto texture = props.TextureOf(key))
    return TexturedValue(std::move(texture)).Clamped(0.0f, std::numeric_limits<float>::max());
  const double value = props.Float(key, fallback);
  if (!(value >= 0.0 && std::isfinite(value))) throw Error("property '" + key + "' must be a finite number ≥ 0");
  return TexturedValue(float(value));
}

inline PbrtRoughness ReadPbrtRoughness(const Properties& props, const std::string& prefix) {
  const TexturedValue both = ReadNonNegative(props, prefix + "roughness", 0.0f);
  PbrtRoughness out;
  out.u = props.Has(prefix + "uroughness") ? ReadNonNegative(props, prefix + "uroughness", 0.0f) : both;
  out.v = props.Has(prefix + "vroughness") ? ReadNonNegative(props, prefix + "vroughness", 0.0f) : both;
  out.remap = props.Bool("remaproughness", true);
  return out;
}

// The parameters ReadPbrtRoughness reads under `prefix`, without
// remaproughness (one for both layers: RemapParameter). uroughness and
// vroughness have no declared default: left out, they are roughness.
inline std::vector<Parameter> PbrtRoughnessParameters(const std::string& prefix, const std::string& layer) {
  return {
      Parameter::FloatTexture(prefix + "roughness").Default(0.0).Min(0).Doc(layer + "'s GGX roughness"),
      Parameter::FloatTexture(prefix + "uroughness").Min(0).Doc(layer + "'s roughness along x; default roughness"),
      Parameter::FloatTexture(prefix + "vroughness").Min(0).Doc(layer + "'s roughness along y; default roughness"),
  };
}

inline Parameter RemapParameter() {
  return Parameter::Bool("remaproughness")
      .Default(true)
      .Doc("α = √roughness (else α = roughness); α < 10⁻³ is smooth");
}

// The parameters of the slab and the walk, which both coated models read
// under pbrt's names.
struct Slab {
  TexturedValue thickness, albedo, g;
  float eta = 1.5f;
  int max_depth = 10, samples = 1;

  struct Points {
    PointValues<float> thickness, g;
    PointValues<Vec3> albedo;
  };
  Points At(const SurfacePoints& at) const { return {thickness.FloatsAt(at), g.FloatsAt(at), albedo.At(at)}; }
  bool MayScatter() const { return !albedo.IsZero(); }
};

inline Slab ReadSlab(const Properties& props, const std::string& eta_key) {
  Slab slab;
  if (auto texture = props.TextureOf("thickness")) {
    slab.thickness = TexturedValue(std::move(texture)).Clamped(std::numeric_limits<float>::min(), 1e30f);
  } else {
    const double thickness = props.Float("thickness", 0.01);
    if (!(thickness > 0.0 && std::isfinite(thickness)))
      throw Error("property 'thickness' must be a finite number > 0");
    slab.thickness = TexturedValue(float(thickness));
  }
  slab.albedo = TexturedValue::Color(props, "albedo", Vec3(), /*unit=*/true);
  if (auto texture = props.TextureOf("g")) {
    slab.g = TexturedValue(std::move(texture)).Clamped(-0.999f, 0.999f);
  } else {
    const double g = props.Float("g", 0.0);
    if (!(g > -1.0 && g < 1.0)) throw Error("property 'g' must be a number in (-1, 1)");
    slab.g = TexturedValue(float(g));
  }
  const double eta = props.Float(eta_key, 1.5);
  if (!(eta > 0.0 && std::isfinite(eta))) throw Error("property '" + eta_key + "' must be a finite number > 0");
  slab.eta = float(eta);
  slab.max_depth = int(props.Int("maxdepth", 10, 1, 1000));
  slab.samples = int(props.Int("nsamples", 1, 1, 1000));
  return slab;
}

// The parameters ReadSlab reads, the coat's index under `eta_key`.
inline std::vector<Parameter> SlabParameters(const std::string& eta_key) {
  return {
      Parameter::Float(eta_key).Default(1.5).Min(0).Doc("the coat's index over the outside's, > 0"),
      Parameter::FloatTexture("thickness").Default(0.01).Min(0).Doc("the slab's thickness, > 0, in mean free paths"),
      Parameter::RgbTexture("albedo").Default(0.0).Range(0, 1).Doc("the slab medium's albedo (0: no medium)"),
      Parameter::FloatTexture("g").Default(0.0).Range(-1, 1).Doc("the slab's phase function's asymmetry, in (-1, 1)"),
      Parameter::Int("maxdepth").Default(10).Range(1, 1000).Doc("the most events of a walk"),
      Parameter::Int("nsamples").Default(1).Range(1, 1000).Doc("walks per evaluation"),
  };
}

// --- The SurfaceModel calls ---------------------------------------------------

// Evaluate, Sample and Pdf of a layered model, given the Layers at each
// row (`layers_at(k)`). Sample returns, for non-delta directions, pdf =
// Density(wi, wo) with the seed Pdf uses, so Sample's and Pdf's densities
// are one function (see the plugins' header comments).
template <typename LayersAt>
void EvaluateRows(const LayersAt& layers_at, TransportMode mode, std::span<const float> wi,
                  std::span<const float> wo, const SurfacePoints& at, std::span<float> value) {
  const size_t count = wi.size() / 3;
  for (size_t k = 0; k < count; ++k) {
    const Vec3 v = Vec3::Load(&wi[3 * k]), l = Vec3::Load(&wo[3 * k]);
    Rng r(Seed(1, v, l, at, k));
    layers_at(k).Value(v, l, mode, r).Store(&value[3 * k]);
  }
}

template <typename LayersAt>
float DensityRow(const LayersAt& layers_at, size_t k, Vec3 v, Vec3 l, const SurfacePoints& at) {
  Rng r(Seed(2, v, l, at, k));
  // The density of the radiance walk: Pdf has no mode, and the two differ
  // only in the η² of the top's transmissions, which cancel in it.
  return layers_at(k).Density(v, l, TransportMode::kRadiance, r);
}

template <typename LayersAt>
void PdfRows(const LayersAt& layers_at, std::span<const float> wi, std::span<const float> wo,
             const SurfacePoints& at, std::span<float> pdf) {
  const size_t count = wi.size() / 3;
  for (size_t k = 0; k < count; ++k)
    pdf[k] = DensityRow(layers_at, k, Vec3::Load(&wi[3 * k]), Vec3::Load(&wo[3 * k]), at);
}

// Sample's rows: the walk's direction and weight; its pdf, for a delta
// path, the path's discrete probability, and otherwise DensityRow at the
// drawn direction, the function Pdf gives (so MIS weighs both strategies
// with one density). A lobe `allowed` excludes gives no sample.
template <typename LayersAt>
void SampleEach(const LayersAt& layers_at, TransportMode mode, std::span<const float> wi, const SurfacePoints& at,
                std::span<const float> uniform, uint32_t allowed, const SampleRows& rows) {
  const size_t count = wi.size() / 3;
  for (size_t k = 0; k < count; ++k) {
    const auto layers = layers_at(k);
    const Vec3 v = Vec3::Load(&wi[3 * k]);
    const float* u = &uniform[3 * k];
    Rng r(Seed(3, v, Vec3(u[0], u[1], u[2]), at, k));
    typename std::remove_cvref_t<decltype(layers)>::Drawn drawn;
    if (!layers.Sample(v, u[0], u[1], u[2], mode, r, &drawn)) {
      rows.StoreNoSample(k);
      continue;
    }
    const uint32_t lobe = kScatterReflect | (drawn.delta            ? kScatterDelta
                                             : drawn.top_reflection ? kScatterGlossy
                                                                    : layers.WalkKind());
    const float density = drawn.delta ? drawn.pdf : DensityRow(layers_at, k, v, drawn.l, at);
    if (!LobeAllowed(lobe, allowed) || !(density > 0)) {
      rows.StoreNoSample(k);
      continue;
    }
    rows.Store(k, drawn.l, drawn.weight, density, lobe);
  }
}

// A layered material's SurfaceModel: Model::LayersAt(at) gives the layers
// at the points of a call, and Evaluate, Sample and Pdf walk them.
template <typename Model>
class LayeredSurfaceModel : public SurfaceModel {
 public:
  void Evaluate(TransportMode mode, std::span<const float> wi, std::span<const float> wo, const SurfacePoints& at,
                std::span<float> value) const final {
    EvaluateRows(Self().LayersAt(at), mode, wi, wo, at, value);
  }
  void Sample(TransportMode mode, std::span<const float> wi, const SurfacePoints& at, std::span<const float> uniform,
              uint32_t allowed, std::span<float> wo, std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const final {
    SampleEach(Self().LayersAt(at), mode, wi, at, uniform, allowed, SampleRows{wo, weight, pdf, flags});
  }
  void Pdf(std::span<const float> wi, std::span<const float> wo, const SurfacePoints& at,
           std::span<float> pdf) const final {
    PdfRows(Self().LayersAt(at), wi, wo, at, pdf);
  }

 private:
  const Model& Self() const { return static_cast<const Model&>(*this); }
};

}  // namespace yarf::layered
