// hair — scattering by a human hair fibre: pbrt-v4's `hair` material
// (HairBxDF), the model of Chiang, Bitterli, Tappan and Burley, "A
// Practical and Controllable Hair and Fur Model for Production Path
// Tracing" (Computer Graphics Forum 35(2), 2016), on d'Eon's energy-
// conserving longitudinal lobes and Marschner's fibre of scales.
//
// The fibre is a dielectric cylinder (index eta) whose interior absorbs
// (sigma_a, per unit of the fibre's radius). Light leaves it after p
// internal paths: reflected at once (R, p = 0), transmitted through (TT,
// p = 1), reflected once inside (TRT, p = 2), and the rest summed into one
// lobe. Each is a product of a longitudinal lobe Mp (a von Mises–Fisher-
// like lobe about the cone of directions at the reflected angle, its
// variance from beta_m, tilted by the scales' angle alpha), an attenuation
// Ap (Fresnel and absorption along the path) and an azimuthal lobe Np (a
// logistic of scale from beta_n about the exit angle the path's
// refractions give). The rest is isotropic in azimuth.
//
// The shading frame: x along the fibre (the curve's ∂p/∂u), z the surface
// normal. The offset h ∈ [-1, 1] at which the light that found the point
// met the fibre is read from that light's direction wi and the normal of
// the tube (a round curve's; on a flat ribbon facing the ray it is 0, the
// fibre's centre): h = sin γ, γ the angle between the normal and wi seen
// along the fibre. As in pbrt, the model is that of the fibre met at h,
// whatever direction it is evaluated toward.
//
// Absorption: sigma_a directly, else from a `reflectance` (the colour a
// fibre of it shows after many bounces, Chiang et al.'s inversion for the
// given beta_n), else from melanin concentrations (eumelanin, pheomelanin;
// pbrt's default is eumelanin 1.3, brown hair).
//
// Sample chooses the lobe p by the share of its attenuation (averaged over
// the channels), then θ from Mp and the azimuth from Np (a trimmed
// logistic) or uniformly for the rest; the pdf sums every lobe's. Directions
// reach the whole sphere: a sample is a reflection when it stays on wi's
// side of the normal, a transmission when it crosses.
#include <array>
#include <cmath>
#include <cstdint>
#include <span>

#include "yarf/plugin.h"
#include "yarf/support/scatter_rows.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

constexpr int kLobes = 3;  // R, TT, TRT; the rest summed as lobe kLobes
constexpr float kPi = 3.14159265358979f;
constexpr uint32_t kReflectLobe = yarf::kScatterReflect | yarf::kScatterGlossy;
constexpr uint32_t kTransmitLobe = yarf::kScatterRefract | yarf::kScatterGlossy;

float Sqr(float x) { return x * x; }
float SafeSqrt(float x) { return std::sqrt(std::max(0.0f, x)); }
float SafeAsin(float x) { return std::asin(std::clamp(x, -1.0f, 1.0f)); }

// The modified Bessel function of the first kind I0, by its series, and
// its logarithm (asymptotic for large x, where the series overflows).
float I0(float x) {
  float value = 0, x2i = 1;
  double factorial = 1, four_i = 1;
  for (int i = 0; i < 10; ++i) {
    if (i > 1) factorial *= i;
    value += float(x2i / (four_i * factorial * factorial));
    x2i *= x * x;
    four_i *= 4;
  }
  return value;
}
float LogI0(float x) {
  if (x > 12) return x + 0.5f * (-std::log(2 * kPi) + std::log(1 / x) + 1 / (8 * x));
  return std::log(I0(x));
}

// d'Eon's longitudinal lobe of variance v.
float Mp(float cos_i, float cos_o, float sin_i, float sin_o, float v) {
  const float a = cos_i * cos_o / v, b = sin_i * sin_o / v;
  if (v <= 0.1f) return std::exp(LogI0(a) - b - 1 / v + 0.6931f + std::log(1 / (2 * v)));
  return std::exp(-b) * I0(a) / (std::sinh(1 / v) * 2 * v);
}

float Logistic(float x, float s) {
  x = std::abs(x);
  return std::exp(-x / s) / (s * Sqr(1 + std::exp(-x / s)));
}
float LogisticCdf(float x, float s) { return 1 / (1 + std::exp(-x / s)); }
// The logistic of scale s restricted to [-π, π], normalised there.
float TrimmedLogistic(float x, float s) { return Logistic(x, s) / (LogisticCdf(kPi, s) - LogisticCdf(-kPi, s)); }
float SampleTrimmedLogistic(float u, float s) {
  const float k = LogisticCdf(kPi, s) - LogisticCdf(-kPi, s);
  const float x = -s * std::log(1 / (u * k + LogisticCdf(-kPi, s)) - 1);
  return std::clamp(x, -kPi, kPi);
}

// The exit azimuth of lobe p for the offsets γo (outside) and γt (inside).
float Phi(int p, float gamma_o, float gamma_t) { return 2 * p * gamma_t - 2 * gamma_o + p * kPi; }

float Np(float phi, int p, float s, float gamma_o, float gamma_t) {
  float dphi = phi - Phi(p, gamma_o, gamma_t);
  dphi = std::remainder(dphi, 2 * kPi);  // into [-π, π]
  return TrimmedLogistic(dphi, s);
}

// sin θ and cos θ of the light's direction as the scales tilt lobe p's cone.
struct Tilted {
  float sin_theta, cos_theta;
};

// What one evaluation at offset h from light direction wi needs.
struct Fibre {
  float sin_theta_o, cos_theta_o, phi_o, gamma_o, gamma_t;
  std::array<Vec3, kLobes + 1> ap;
};

class Hair final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::Rgb("sigma_a").Range(0, 1e4).Doc("absorption inside the fibre, per unit of its radius"),
        P::Rgb("reflectance").Range(1e-4, 1).Doc("the colour to absorb for, when sigma_a is not given"),
        P::Float("eumelanin").Range(0, 100).Doc("eumelanin concentration, when neither colour is given (1.3 if "
                                                  "pheomelanin is not given either)"),
        P::Float("pheomelanin").Range(0, 100).Doc("pheomelanin concentration (0 if not given)"),
        P::Float("eta").Default(1.55).Range(1, 3).Doc("index of refraction of the fibre"),
        P::Float("beta_m").Default(0.3).Range(0.01, 1).Doc("longitudinal roughness"),
        P::Float("beta_n").Default(0.3).Range(0.01, 1).Doc("azimuthal roughness"),
        P::Float("alpha").Default(2.0).Range(-45, 45).Doc("tilt of the fibre's scales, degrees"),
    };
  }

  explicit Hair(const yarf::Properties& props)
      : eta_(float(props.Float("eta", 1.55))),
        beta_m_(float(props.Float("beta_m", 0.3))),
        beta_n_(float(props.Float("beta_n", 0.3))) {
    if (!(eta_ >= 1 && eta_ <= 3)) throw yarf::Error("property 'eta' must be in [1, 3]");
    if (!(beta_m_ >= 0.01f && beta_m_ <= 1)) throw yarf::Error("property 'beta_m' must be in [0.01, 1]");
    if (!(beta_n_ >= 0.01f && beta_n_ <= 1)) throw yarf::Error("property 'beta_n' must be in [0.01, 1]");
    sigma_a_ = Absorption(props);
    for (const float channel : {sigma_a_.x, sigma_a_.y, sigma_a_.z})
      if (!(channel >= 0 && std::isfinite(channel)))
        throw yarf::Error("the hair's absorption must be finite and not negative");
    // Longitudinal variances from beta_m; TT narrower, TRT wider than R.
    v_[0] = Sqr(0.726f * beta_m_ + 0.812f * Sqr(beta_m_) + 3.7f * std::pow(beta_m_, 20.0f));
    v_[1] = 0.25f * v_[0];
    v_[2] = 4 * v_[0];
    v_[kLobes] = v_[2];
    // The azimuthal logistic's scale from beta_n.
    s_ = 0.626657069f * (0.265f * beta_n_ + 1.194f * Sqr(beta_n_) + 5.372f * std::pow(beta_n_, 22.0f));
    // The scales tilt lobe p by -2α, α, 4α: sin and cos of 2^k α.
    const float alpha = float(props.Float("alpha", 2.0));
    if (!(std::abs(alpha) <= 45)) throw yarf::Error("property 'alpha' must be in [-45, 45] degrees");
    sin_2k_alpha_[0] = std::sin(alpha * kPi / 180);
    cos_2k_alpha_[0] = SafeSqrt(1 - Sqr(sin_2k_alpha_[0]));
    for (int i = 1; i < kLobes; ++i) {
      sin_2k_alpha_[i] = 2 * cos_2k_alpha_[i - 1] * sin_2k_alpha_[i - 1];
      cos_2k_alpha_[i] = Sqr(cos_2k_alpha_[i - 1]) - Sqr(sin_2k_alpha_[i - 1]);
    }
  }

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints&,
                std::span<float> value) const override {
    yarf::EvaluateEach(wi, wo, value, [&](size_t, Vec3 in, Vec3 out) {
      const Fibre fibre = FibreFrom(in);
      return Value(fibre, LobeTerms(fibre, out), out);
    });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints&,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const override {
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < wi.size() / 3; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const Fibre fibre = FibreFrom(in);
      const std::array<float, kLobes + 1> share = LobeShares(fibre);
      // The lobe, and the choice's uniform number rescaled for Np.
      float u = uniform[3 * k];
      int p = 0;
      while (p < kLobes && u >= share[p]) u -= share[p++];
      u = std::clamp(u / share[p], 0.0f, std::nextafter(1.0f, 0.0f));
      // θ from Mp about lobe p's tilted cone.
      const Tilted o = TiltedOut(p, fibre);
      const float u0 = uniform[3 * k + 1], u1 = uniform[3 * k + 2];
      const float cos_theta = 1 + v_[p] * std::log(std::max(u0, 1e-5f) + (1 - u0) * std::exp(-2 / v_[p]));
      const float sin_theta = SafeSqrt(1 - Sqr(cos_theta));
      const float sin_i = -cos_theta * o.sin_theta + sin_theta * std::cos(2 * kPi * u1) * o.cos_theta;
      const float cos_i = SafeSqrt(1 - Sqr(sin_i));
      // The azimuth from Np, or uniform for the rest.
      const float dphi =
          p < kLobes ? Phi(p, fibre.gamma_o, fibre.gamma_t) + SampleTrimmedLogistic(u, s_) : 2 * kPi * u;
      const float phi_i = fibre.phi_o + dphi;
      const Vec3 out(sin_i, cos_i * std::cos(phi_i), cos_i * std::sin(phi_i));
      const uint32_t lobe = in.z * out.z >= 0 ? kReflectLobe : kTransmitLobe;
      const std::array<float, kLobes + 1> term = LobeTerms(fibre, out);
      const float density = Density(share, term);
      if (!yarf::LobeAllowed(lobe, allowed) || !(density > 0) || out.z == 0) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, out, Value(fibre, term, out) * (std::abs(out.z) / density), density, lobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints&,
           std::span<float> pdf) const override {
    yarf::PdfEach(wi, wo, pdf, [&](size_t, Vec3 in, Vec3 out) {
      const Fibre fibre = FibreFrom(in);
      return Density(LobeShares(fibre), LobeTerms(fibre, out));
    });
  }

  uint32_t Lobes() const override { return kReflectLobe | kTransmitLobe; }

 private:
  yarf::Vec3 Absorption(const yarf::Properties& props) const {
    if (props.Has("sigma_a")) return props.Color("sigma_a");
    if (props.Has("reflectance")) {
      // Chiang et al.'s fit of the absorption that gives a colour.
      const Vec3 c = props.Color("reflectance");
      const float b = beta_n_;
      const float d = 5.969f - 0.215f * b + 2.532f * Sqr(b) - 10.73f * b * b * b + 5.574f * Sqr(Sqr(b)) +
                      0.245f * b * Sqr(Sqr(b));
      const auto sigma = [&](float channel) { return Sqr(std::log(std::clamp(channel, 1e-4f, 1.0f)) / d); };
      return Vec3(sigma(c.x), sigma(c.y), sigma(c.z));
    }
    const float pheomelanin = float(props.Float("pheomelanin", 0.0));
    const float eumelanin = float(props.Float("eumelanin", props.Has("pheomelanin") ? 0.0 : 1.3));
    if (!(eumelanin >= 0 && pheomelanin >= 0)) throw yarf::Error("melanin concentrations must not be negative");
    return Vec3(0.419f, 0.697f, 1.37f) * eumelanin + Vec3(0.187f, 0.4f, 1.05f) * pheomelanin;
  }

  Fibre FibreFrom(Vec3 in) const {
    Fibre f;
    f.sin_theta_o = std::clamp(in.x, -1.0f, 1.0f);
    f.cos_theta_o = SafeSqrt(1 - Sqr(f.sin_theta_o));
    f.phi_o = std::atan2(in.z, in.y);
    // The offset seen along the fibre: the normal is +z, the light came
    // from (in.y, in.z) in the plane across the fibre.
    const float across = std::sqrt(Sqr(in.y) + Sqr(in.z));
    const float h = across > 0 ? std::clamp(-in.y / across, -1.0f, 1.0f) : 0.0f;
    f.gamma_o = SafeAsin(h);
    // The refracted ray inside: its angles, and one path's transmittance.
    const float sin_theta_t = f.sin_theta_o / eta_, cos_theta_t = SafeSqrt(1 - Sqr(sin_theta_t));
    const float etap = f.cos_theta_o > 0 ? SafeSqrt(Sqr(eta_) - Sqr(f.sin_theta_o)) / f.cos_theta_o : eta_;
    const float sin_gamma_t = h / etap, cos_gamma_t = SafeSqrt(1 - Sqr(sin_gamma_t));
    f.gamma_t = SafeAsin(sin_gamma_t);
    const float length = 2 * cos_gamma_t / std::max(cos_theta_t, 1e-6f);
    const Vec3 t(std::exp(-sigma_a_.x * length), std::exp(-sigma_a_.y * length), std::exp(-sigma_a_.z * length));
    // Attenuations: Fresnel at entry, then one transmission and one more
    // internal reflection per lobe; the rest a geometric series.
    const float fresnel = yarf::FresnelDielectric(f.cos_theta_o * SafeSqrt(1 - Sqr(h)), eta_);
    f.ap[0] = Vec3(fresnel, fresnel, fresnel);
    f.ap[1] = t * Sqr(1 - fresnel);
    for (int p = 2; p < kLobes; ++p) f.ap[p] = f.ap[p - 1] * t * fresnel;
    const auto rest = [&](float last, float t_channel) {
      const float remaining = 1 - t_channel * fresnel;
      return remaining > 0 ? last * fresnel * t_channel / remaining : 0.0f;
    };
    const Vec3& last = f.ap[kLobes - 1];
    f.ap[kLobes] = Vec3(rest(last.x, t.x), rest(last.y, t.y), rest(last.z, t.z));
    return f;
  }

  // Each lobe's Mp · Np toward `out` of the fibre met as `f` says (the
  // residual lobe's Np uniform), the terms f and the density weigh alike.
  // pbrt's wo is yarf's wi (toward where the light that found the point
  // came from), pbrt's wi yarf's wo.
  std::array<float, kLobes + 1> LobeTerms(const Fibre& f, Vec3 out) const {
    const float sin_i = std::clamp(out.x, -1.0f, 1.0f), cos_i = SafeSqrt(1 - Sqr(sin_i));
    const float phi = std::atan2(out.z, out.y) - f.phi_o;
    std::array<float, kLobes + 1> term{};
    for (int p = 0; p < kLobes; ++p) {
      const Tilted o = TiltedOut(p, f);
      term[p] = Mp(cos_i, o.cos_theta, sin_i, o.sin_theta, v_[p]) * Np(phi, p, s_, f.gamma_o, f.gamma_t);
    }
    term[kLobes] = Mp(cos_i, f.cos_theta_o, sin_i, f.sin_theta_o, v_[kLobes]) / (2 * kPi);
    return term;
  }

  // f toward `out`, from its lobe terms: each weighed by its attenuation.
  static Vec3 Value(const Fibre& f, const std::array<float, kLobes + 1>& term, Vec3 out) {
    Vec3 sum;
    for (int p = 0; p <= kLobes; ++p) sum += f.ap[p] * term[p];
    // The lobes are per unit projected solid angle of the fibre; the
    // caller's cosine is the normal's.
    const float cosine = std::abs(out.z);
    return cosine > 0 ? sum / cosine : Vec3();
  }

  // Lobe p's cone, tilted by the scales: R by -2α, TT by α, TRT by 4α.
  Tilted TiltedOut(int p, const Fibre& f) const {
    const float s = f.sin_theta_o, c = f.cos_theta_o;
    switch (p) {
      case 0:
        return {s * cos_2k_alpha_[1] - c * sin_2k_alpha_[1], std::abs(c * cos_2k_alpha_[1] + s * sin_2k_alpha_[1])};
      case 1:
        return {s * cos_2k_alpha_[0] + c * sin_2k_alpha_[0], std::abs(c * cos_2k_alpha_[0] - s * sin_2k_alpha_[0])};
      case 2:
        return {s * cos_2k_alpha_[2] + c * sin_2k_alpha_[2], std::abs(c * cos_2k_alpha_[2] - s * sin_2k_alpha_[2])};
      default:
        return {s, c};
    }
  }

  // The odds of sampling each lobe: its attenuation's channel mean.
  static std::array<float, kLobes + 1> LobeShares(const Fibre& f) {
    std::array<float, kLobes + 1> share{};
    float total = 0;
    for (int p = 0; p <= kLobes; ++p) total += share[p] = (f.ap[p].x + f.ap[p].y + f.ap[p].z) / 3;
    for (float& s : share) s = total > 0 ? s / total : 1.0f / (kLobes + 1);
    return share;
  }

  // Sample's density per solid angle, from the lobe terms: each weighed
  // by the odds of sampling its lobe.
  static float Density(const std::array<float, kLobes + 1>& share, const std::array<float, kLobes + 1>& term) {
    float density = 0;
    for (int p = 0; p <= kLobes; ++p) density += share[p] * term[p];
    return density;
  }

  float eta_, beta_m_, beta_n_;
  Vec3 sigma_a_;
  std::array<float, kLobes + 1> v_{};
  float s_ = 0;
  std::array<float, kLobes> sin_2k_alpha_{}, cos_2k_alpha_{};
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Hair>(registrar, "hair", "1.0.0",
                       "Human hair fibre (pbrt-v4's hair: Chiang et al. 2016), melanin or colour absorption");
}
