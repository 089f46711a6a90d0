// Tests of the metal, microfacet and coated surface plugins (conductor,
// roughconductor, roughdielectric, plastic, roughplastic, pplastic,
// thindielectric, diffusetransmission) and of the helpers they share (microfacet.h,
// metals.h). The plugins are loaded from the plugin folder through the
// registry, as yarfd loads them. For each model with a finite lobe:
// Pearson's χ² test of Sample's directions against Pdf, Sample agreeing
// with Pdf and Evaluate, Pdf integrating to the rate at which Sample
// succeeds (≤ 1), reciprocity, energy conservation (white furnace), and
// the limit α → 0 against the smooth model; for the delta lobes, exact
// directions and probabilities; and property checking.
//
// The fixture, batch-call and χ² binning helpers are
// surface_test_support.h's, shared with bsdf_test.cc; the sphere
// quadrature here is uniform in θ rather than cos θ, to resolve lobes
// near the pole.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "metals.h"
#include "microfacet.h"
#include "surface_test_support.h"
#include "yarf/surface.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

using namespace surface_testing;  // NOLINT: the shared helpers, in every test
namespace mf = microfacet;

constexpr TransportMode kRadiance = TransportMode::kRadiance;
constexpr TransportMode kImportance = TransportMode::kImportance;

// Incident directions from normal to grazing incidence (cos θ = 0.05).
std::vector<Vec3> Above() {
  std::vector<Vec3> out;
  for (float cos_theta : {1.0f, 0.8f, 0.5f, 0.2f, 0.05f})
    out.push_back(DirectionAt(cos_theta, 0.7 + 2.0 * cos_theta));
  return out;
}

// The same, and their mirror images below the surface.
std::vector<Vec3> BothSides() {
  std::vector<Vec3> out = Above();
  for (Vec3 w : Above()) out.push_back(Vec3(w.y, w.x, -w.z));
  return out;
}

// The finite-lobe samples of `count` draws at wi follow Pdf.
testing::AssertionResult SamplesFollowPdf(const SurfaceModel& model, Vec3 wi, int count,
                                          uint64_t seed) {
  std::vector<Vec3> directions;
  for (const Scattered& s : SampleMany(model, wi, count, seed))
    if (s.pdf > 0 && !(s.flags & kScatterDelta)) directions.push_back(s.wo);
  return DirectionsFollowPdf(model, wi, directions, count);
}

// --- Fixtures ----------------------------------------------------------------

class MicrofacetTest : public SurfacePluginTest {
 protected:
  // Every sample with pdf > 0 has the pdf Pdf gives and the weight
  // Evaluate·|cos θo|/Pdf; its flags are one of the model's lobes, on the
  // side they say. Returns the number of samples produced.
  int ExpectSampleAgreesWithPdfAndEvaluate(const SurfaceModel& model, Vec3 wi, int count,
                                           uint64_t seed, TransportMode mode,
                                           const std::string& name) const {
    int produced = 0;
    for (const Scattered& s : SampleMany(model, wi, count, seed, 0, mode)) {
      if (!(s.pdf > 0)) {
        EXPECT_EQ(s.flags, uint32_t(kScatterNone)) << name;
        ExpectVecNear(s.weight, Vec3(), 0, name + " weight without a sample");
        continue;
      }
      if (s.flags & kScatterDelta) continue;
      ++produced;
      const std::string where = name + " wi " + Describe(wi) + " wo " + Describe(s.wo);
      EXPECT_EQ(s.flags & ~model.Lobes(), 0u) << where;
      EXPECT_NEAR(Length(s.wo), 1.0f, 1e-4f) << where;
      if (s.flags & kScatterReflect) {
        EXPECT_GT(wi.z * s.wo.z, 0.0f) << where;
      } else {
        EXPECT_LT(wi.z * s.wo.z, 0.0f) << where;
      }
      const float pdf = PdfOne(model, wi, s.wo);
      EXPECT_NEAR(s.pdf, pdf, 1e-4f * std::max(1.0f, pdf)) << where;
      ExpectVecNear(s.weight, EvaluateOne(model, wi, s.wo, mode) * (std::abs(s.wo.z) / pdf),
                    1e-3f, where);
    }
    return produced;
  }

  // For the rough model `name` at α = 0.2 and 0.6: ∫ Pdf dωo is at most 1,
  // and it is the fraction of 100000 draws (from `seed`) at each wi that
  // Sample turns into a sample.
  void ExpectPdfIntegratesToTheRateOfSamples(const std::string& name,
                                             std::initializer_list<Vec3> incident,
                                             uint64_t seed) const {
    for (double alpha : {0.2, 0.6}) {
      const auto model = Make(name, Props({{"alpha", alpha}}));
      for (Vec3 wi : incident) {
        const double integral = IntegrateOverSphere(*model, wi).pdf;
        const double rate = MeanWeight(SampleMany(*model, wi, 100000, seed)).success;
        EXPECT_LE(integral, 1.0 + 2e-3) << "alpha " << alpha << ", wi " << Describe(wi);
        EXPECT_NEAR(integral, rate, 6e-3) << "alpha " << alpha << ", wi " << Describe(wi);
      }
    }
  }

  // f(a, b) = f(b, a) for 2000 pairs of directions on the sphere (from
  // seeds `seed` and `seed` + 1), and f and Pdf are 0 unless both lie
  // above: the one-sided rough models.
  static void ExpectReciprocalAndOneSided(const SurfaceModel& model, uint64_t seed) {
    for (uint64_t k = 0; k < 2000; ++k) {
      const auto u = Uniform3(seed, k), v = Uniform3(seed + 1, k);
      const Vec3 a = SampleUniformSphere(u[0], u[1]), b = SampleUniformSphere(v[0], v[1]);
      const Vec3 f = EvaluateOne(model, a, b);
      ExpectVecNear(f, EvaluateOne(model, b, a), 1e-4f, "f(a, b) vs f(b, a)");
      if (a.z <= 0 || b.z <= 0) {
        ExpectVecNear(f, Vec3(), 0, "below");
        EXPECT_EQ(PdfOne(model, a, b), 0.0f);
      }
    }
  }
};

class ConductorTest : public MicrofacetTest {};
class RoughConductorTest : public MicrofacetTest {};
class RoughDielectricTest : public MicrofacetTest {
 protected:
  static constexpr float kEta = float(1.5046 / 1.000277);  // the defaults
  // η of wo's side over wi's side for a refraction.
  static float RefractedEta(Vec3 wi) { return wi.z > 0 ? kEta : 1.0f / kEta; }
};
class PlasticTest : public MicrofacetTest {
 protected:
  static constexpr float kEta = float(1.49 / 1.000277);  // the defaults
};
class RoughPlasticTest : public MicrofacetTest {};
class PPlasticTest : public PlasticTest {};
class ThinDielectricTest : public MicrofacetTest {};
class DiffuseTransmissionTest : public MicrofacetTest {};

const char* const kNewModels[] = {"conductor",      "roughconductor", "roughdielectric",
                                  "plastic",        "roughplastic",   "pplastic",
                                  "thindielectric", "diffusetransmission"};

// --- Shared helpers (microfacet.h, metals.h) -------------------------------

TEST_F(MicrofacetTest, FresnelConductorWithoutAbsorptionIsTheDielectricOne) {
  for (float eta : {1.5f, 1.33f, 2.4f, 0.7f})
    for (int i = 0; i <= 100; ++i) {
      const float cos_i = i / 100.0f;
      EXPECT_NEAR(mf::FresnelConductor(cos_i, eta, 0.0f), FresnelDielectric(cos_i, eta), 2e-5f)
          << "eta " << eta << ", cos θi " << cos_i;
    }
}

// The Fresnel equations with the complex index itself (Born & Wolf's
// amplitudes), in double: the real-arithmetic form must agree at every
// angle, for every named metal.
TEST_F(MicrofacetTest, FresnelConductorIsTheComplexFresnelEquations) {
  using Complex = std::complex<double>;
  for (const metals::NamedMetal& metal : metals::kMetals)
    for (int c = 0; c < 3; ++c) {
      const Complex n(metal.ior.eta[c], metal.ior.k[c]);
      for (int i = 1; i <= 200; ++i) {
        const double cos_i = i / 200.0, sin2 = 1 - cos_i * cos_i;
        const Complex cos_t = std::sqrt(1.0 - sin2 / (n * n));
        const double r_p = std::norm((n * cos_i - cos_t) / (n * cos_i + cos_t));
        const double r_s = std::norm((cos_i - n * cos_t) / (cos_i + n * cos_t));
        EXPECT_NEAR(mf::FresnelConductor(float(cos_i), float(n.real()), float(n.imag())), 0.5 * (r_p + r_s), 2e-5)
            << metal.name << ", cos θi " << cos_i;
      }
    }
}

TEST_F(MicrofacetTest, FresnelConductorAtNormalAndGrazingIncidence) {
  for (const metals::NamedMetal& metal : metals::kMetals)
    for (int c = 0; c < 3; ++c) {
      const float n = metal.ior.eta[c], k = metal.ior.k[c];
      const float normal = ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k);
      EXPECT_NEAR(mf::FresnelConductor(1.0f, n, k), normal, 1e-5f) << metal.name;
      EXPECT_NEAR(mf::FresnelConductor(0.0f, n, k), 1.0f, 1e-5f) << metal.name;
      for (int i = 0; i <= 100; ++i) {
        const float fresnel = mf::FresnelConductor(i / 100.0f, n, k);
        EXPECT_GE(fresnel, 0.0f) << metal.name;
        EXPECT_LE(fresnel, 1.0f) << metal.name;
      }
    }
  // Mitsuba's perfect mirror: η = 0, κ = 1.
  for (int i = 0; i <= 100; ++i)
    EXPECT_NEAR(mf::FresnelConductor(i / 100.0f, 0.0f, 1.0f), 1.0f, 1e-6f) << i;
}

TEST_F(MicrofacetTest, NamedMetalsHaveTheirColours) {
  const auto reflectance = [](const char* name) {
    for (const metals::NamedMetal& metal : metals::kMetals)
      if (std::string(name) == metal.name)
        return mf::FresnelConductor(1.0f, metal.ior.eta, metal.ior.k);
    ADD_FAILURE() << "no metal " << name;
    return Vec3();
  };
  // Gold and copper reflect red most and blue least; silver and aluminium
  // nearly all light, nearly grey.
  for (const char* name : {"Au", "Cu"}) {
    const Vec3 r = reflectance(name);
    EXPECT_GT(r.x, r.y) << name;
    EXPECT_GT(r.y, r.z) << name;
    EXPECT_GT(r.x, 0.9f) << name;
  }
  for (const char* name : {"Ag", "Al"}) {
    const Vec3 r = reflectance(name);
    EXPECT_GT(std::min({r.x, r.y, r.z}), 0.85f) << name;
    EXPECT_LT(MaxComponent(r) - std::min({r.x, r.y, r.z}), 0.1f) << name;
  }
  // Every named metal is a conductor the models accept, reflecting at
  // most everything at every angle.
  EXPECT_GE(std::size(metals::kMetals), 60u);
  for (const metals::NamedMetal& metal : metals::kMetals) {
    EXPECT_NO_THROW(Make("conductor", Props({{"material", std::string(metal.name)}}))) << metal.name;
    for (float cos : {1.0f, 0.5f, 0.01f}) {
      const Vec3 r = mf::FresnelConductor(cos, metal.ior.eta, metal.ior.k);
      EXPECT_TRUE(std::min({r.x, r.y, r.z}) >= 0 && MaxComponent(r) <= 1) << metal.name;
    }
  }
}

TEST_F(MicrofacetTest, SmithG2LiesBetweenSeparableAndMinimum) {
  for (const mf::Distribution d : {mf::Distribution::kGgx, mf::Distribution::kBeckmann})
  for (auto [ax, ay] : {std::pair{0.1f, 0.1f}, std::pair{0.5f, 0.5f}, std::pair{0.2f, 0.8f}})
    for (uint64_t k = 0; k < 2000; ++k) {
      const auto u = Uniform3(61, k), v = Uniform3(62, k);
      const Vec3 a = SampleUniformSphere(u[0], u[1]), b = SampleUniformSphere(v[0], v[1]);
      const mf::Roughness r{ax, ay, d};
      const float g1a = mf::SmithG1(a, r), g1b = mf::SmithG1(b, r);
      const float g2 = mf::SmithG2(a, b, r);
      EXPECT_NEAR(g2, mf::SmithG2(b, a, r), 1e-6f);
      EXPECT_GE(g2, g1a * g1b - 1e-6f);
      EXPECT_LE(g2, std::min(g1a, g1b) + 1e-6f);
    }
  EXPECT_NEAR(mf::SmithG2(DirectionAt(0.3, 1.0), DirectionAt(0.6, 2.0), mf::Roughness{1e-4f, 1e-4f}), 1.0f,
              1e-5f);
}

TEST_F(MicrofacetTest, BeckmannNormalsAndVisibleNormalsAreDensities) {
  // ∫ D(m) cos θm dωm = 1, and ∫ D_wi(m) dωm = 1 for any wi: the midpoint
  // rule over (cos θ, φ) of the upper hemisphere.
  for (auto [ax, ay] : {std::pair{0.1f, 0.1f}, std::pair{0.4f, 0.4f}, std::pair{0.15f, 0.6f}}) {
    const mf::Roughness r{ax, ay, mf::Distribution::kBeckmann};
    constexpr int kRows = 4000, kCols = 256;
    for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.5, 1.0), DirectionAt(0.1, -2.0)}) {
      double projected = 0, visible = 0;
      for (int i = 0; i < kRows; ++i)
        for (int j = 0; j < kCols; ++j) {
          const float z = (i + 0.5f) / kRows, phi = (j + 0.5f) * 2 * kPi / kCols;
          const float sin = std::sqrt(1 - z * z);
          const Vec3 m(sin * std::cos(phi), sin * std::sin(phi), z);
          projected += mf::Ndf(m, r) * z;
          visible += mf::VisibleNormalPdf(wi, m, r);
        }
      const double cell = (1.0 / kRows) * (2 * kPi / kCols);
      EXPECT_NEAR(projected * cell, 1.0, 2e-3) << ax << " " << ay;
      EXPECT_NEAR(visible * cell, 1.0, 3e-3) << ax << " " << ay << ", wi " << Describe(wi);
    }
  }
  for (float y : {-0.999f, -0.5f, 0.0f, 0.3f, 0.9f, 0.99999f})
    EXPECT_NEAR(std::erf(mf::ErfInv(y)), y, 1e-6f) << y;
}

TEST_F(MicrofacetTest, RefractAboutFollowsSnell) {
  constexpr float kEta = 1.5f;
  int refracted = 0;
  for (uint64_t k = 0; k < 2000; ++k) {
    const auto u = Uniform3(63, k), v = Uniform3(64, k);
    const Vec3 m = SampleCosineHemisphere(u[0], u[1]);
    const Vec3 wi = SampleUniformSphere(v[0], v[1]);
    Vec3 wt;
    if (!mf::RefractAbout(wi, m, kEta, &wt)) {
      // Total internal reflection: only from the dense side.
      EXPECT_LT(Dot(wi, m), 0.0f);
      continue;
    }
    ++refracted;
    const float cos_i = Dot(wi, m), cos_t = Dot(wt, m);
    const float eta_i = cos_i > 0 ? 1.0f : kEta, eta_t = cos_i > 0 ? kEta : 1.0f;
    EXPECT_NEAR(Length(wt), 1.0f, 1e-5f);
    EXPECT_LT(cos_i * cos_t, 0.0f);
    EXPECT_NEAR(eta_i * SinFromCos(cos_i), eta_t * SinFromCos(cos_t), 1e-4f);
    // wi, m and wt lie in one plane.
    EXPECT_NEAR(Dot(Cross(wi, m), wt), 0.0f, 1e-4f);
  }
  EXPECT_GT(refracted, 1000);
  // About +z it is warps.h's Refract.
  const Vec3 wi = DirectionAt(0.6, 0.4);
  Vec3 about_m, about_z;
  ASSERT_TRUE(mf::RefractAbout(wi, Vec3(0, 0, 1), kEta, &about_m));
  ASSERT_TRUE(Refract(wi, kEta, &about_z));
  ExpectVecNear(about_m, about_z, 1e-6f, "RefractAbout(+z)");
}

TEST_F(MicrofacetTest, DiffuseFresnelReflectance) {
  // Hemispherical average of glass's reflectance: 0.0918 from outside
  // (the classic value ≈ 0.092) and 0.596 from inside.
  EXPECT_NEAR(mf::FresnelDiffuseReflectance(1.5f), 0.0918f, 5e-4f);
  EXPECT_NEAR(mf::FresnelDiffuseReflectance(1.0f / 1.5f), 0.596f, 1e-3f);
  // From inside, integrated directly (total internal reflection included).
  for (float eta : {1.33f, 1.5f, 2.0f}) {
    constexpr int kSteps = 200000;
    double sum = 0;
    for (int i = 0; i < kSteps; ++i) {
      const double mu = (i + 0.5) / kSteps;
      sum += 2 * FresnelDielectric(-float(mu), eta) * mu / kSteps;
    }
    EXPECT_NEAR(mf::FresnelDiffuseReflectance(1.0f / eta), sum, 2e-4) << "eta " << eta;
  }
  EXPECT_NEAR(mf::FresnelDiffuseReflectance(1.0f), 0.0f, 1e-6f);
}

TEST_F(MicrofacetTest, RoughInterfaceReflectanceTendsToFresnel) {
  for (float eta : {1.5f, 1.0f / 1.5f})
    for (float cos_theta : {1.0f, 0.7f, 0.4f, 0.1f}) {
      const float smooth = FresnelDielectric(cos_theta, eta);
      EXPECT_NEAR(mf::RoughDielectricReflectance(cos_theta, mf::Roughness{1e-3f, 1e-3f}, eta), smooth, 2e-3f)
          << "eta " << eta << ", cos θ " << cos_theta;
      // Roughness spreads the reflection, and loses some below the horizon.
      EXPECT_LE(mf::RoughDielectricReflectance(cos_theta, mf::Roughness{0.5f, 0.5f}, eta), 1.0f);
    }
}

TEST_F(MicrofacetTest, ChiSquareTestTellsCloseModelsApart) {
  // A control for the tests below: samples of one model fail against the
  // Pdf of a slightly different one.
  const auto expect_rejected = [&](const Properties& sampled, const Properties& other,
                                   const char* name, Vec3 wi) {
    const auto model = Make(name, sampled);
    std::vector<Vec3> directions;
    for (const Scattered& s : SampleMany(*model, wi, 200000, 141))
      if (s.pdf > 0) directions.push_back(s.wo);
    EXPECT_FALSE(DirectionsFollowPdf(*Make(name, other), wi, directions, 200000))
        << name << " at wi " << Describe(wi);
  };
  expect_rejected(Props({{"alpha", 0.2}}), Props({{"alpha", 0.22}}), "roughconductor",
                  DirectionAt(0.7, 0.5));
  expect_rejected(Props({{"alpha", 0.2}}), Props({{"alpha", 0.2}, {"int_ior", 1.45}}),
                  "roughdielectric", Vec3(0, 0, 1));
  expect_rejected(Props({{"alpha", 0.2}}), Props({{"alpha", 0.2}, {"diffuse_reflectance", 0.6}}),
                  "roughplastic", DirectionAt(0.5, 1.0));
}

// --- Registration and properties -------------------------------------------

TEST_F(MicrofacetTest, RegistersEveryModelWithItsInterfaceAndLobes) {
  for (const char* name : kNewModels) ASSERT_NO_FATAL_FAILURE(ExpectRegisteredSurfaceModel(name));
  EXPECT_EQ(Make("conductor")->Lobes(), uint32_t(kScatterReflect | kScatterDelta));
  EXPECT_EQ(Make("roughconductor")->Lobes(), uint32_t(kScatterReflect | kScatterGlossy));
  EXPECT_EQ(Make("roughdielectric")->Lobes(),
            uint32_t(kScatterReflect | kScatterRefract | kScatterGlossy));
  EXPECT_EQ(Make("plastic")->Lobes(), uint32_t(kScatterReflect | kScatterDelta | kScatterDiffuse));
  EXPECT_EQ(Make("roughplastic")->Lobes(),
            uint32_t(kScatterReflect | kScatterGlossy | kScatterDiffuse));
  EXPECT_EQ(Make("pplastic")->Lobes(), uint32_t(kScatterReflect | kScatterGlossy | kScatterDiffuse));
  EXPECT_EQ(Make("thindielectric")->Lobes(),
            uint32_t(kScatterReflect | kScatterRefract | kScatterDelta));
  EXPECT_EQ(Make("diffusetransmission")->Lobes(),
            uint32_t(kScatterReflect | kScatterRefract | kScatterDiffuse));
  EXPECT_EQ(Make("diffusetransmission", Props({{"transmittance", 0.0}}))->Lobes(),
            uint32_t(kScatterReflect | kScatterDiffuse));
  EXPECT_EQ(Make("plastic", Props({{"diffuse_reflectance", 0.0}}))->Lobes(),
            uint32_t(kScatterReflect | kScatterDelta));
}

TEST_F(MicrofacetTest, BadPropertiesAreRejectedByName) {
  const auto expect_error = [&](const char* name, const Properties& props,
                                std::initializer_list<const char*> mentions) {
    const std::string message = CreationError(name, props);
    EXPECT_FALSE(message.empty()) << name;
    for (const char* text : mentions)
      EXPECT_NE(message.find(text), std::string::npos) << name << ": " << message;
  };
  for (const char* name : {"roughconductor", "roughdielectric", "roughplastic", "pplastic"}) {
    expect_error(name, Props({{"alpha", -0.1}}), {"'alpha'"});
    expect_error(name, Props({{"alpha", 0.0}}), {"'alpha'"});
    expect_error(name, Props({{"distribution", std::string("phong")}}), {"'distribution'"});
  }
  expect_error("roughconductor", Props({{"alpha_u", 0.1}}), {"'alpha_v'"});
  expect_error("roughconductor", Props({{"alpha_u", 0.1}, {"alpha_v", -2.0}}), {"'alpha_v'"});
  expect_error("roughdielectric", Props({{"alpha", 0.1}, {"alpha_v", 0.2}}), {"'alpha'"});
  expect_error("roughplastic", Props({{"alpha_u", 0.1}, {"alpha_v", 0.2}}), {"'alpha_u'"});
  for (const char* name : {"conductor", "roughconductor"}) {
    expect_error(name, Props({{"material", std::string("Unobtainium")}}),
                 {"'material'", "Unobtainium", "Au"});
    expect_error(name, Props({{"material", std::string("Au")}, {"eta", 0.2}}),
                 {"'material'", "'eta'"});
    expect_error(name, Props({{"eta", Rgb{Vec3(0.2f, -1.0f, 0.3f)}}}), {"'eta'"});
    expect_error(name, Props({{"eta", 0.0}, {"k", 0.0}}), {"'eta'", "'k'"});
    expect_error(name, Props({{"specular_reflectance", 1.5}}), {"'specular_reflectance'"});
  }
  expect_error("roughdielectric", Props({{"int_ior", 1.33}, {"ext_ior", 1.33}}),
               {"'int_ior'", "'ext_ior'"});
  for (const char* name : {"roughdielectric", "plastic", "roughplastic", "pplastic", "thindielectric"}) {
    expect_error(name, Props({{"int_ior", -1.5}}), {"'int_ior'"});
    expect_error(name, Props({{"ext_ior", 0.0}}), {"'ext_ior'"});
  }
  for (const char* name : {"plastic", "roughplastic", "pplastic"})
    expect_error(name, Props({{"diffuse_reflectance", 1.2}}), {"'diffuse_reflectance'"});
  expect_error("diffusetransmission", Props({{"reflectance", 0.6}, {"transmittance", 0.6}}),
               {"'reflectance'", "'transmittance'"});
  for (const char* name : kNewModels)
    expect_error(name, Props({{"alpah", 0.5}}), {"'alpah'"});
}

// --- conductor ---------------------------------------------------------------

TEST_F(ConductorTest, ReflectsExactlyWithTheConductorFresnelFactor) {
  const Vec3 specular(0.9f, 0.8f, 1.0f);
  const auto model = Make("conductor", Props({{"material", std::string("Au")},
                                              {"specular_reflectance", Rgb{specular}}}));
  const auto named_gold = std::find_if(std::begin(metals::kMetals), std::end(metals::kMetals),
                                       [](const metals::NamedMetal& m) { return std::string(m.name) == "Au"; });
  ASSERT_NE(named_gold, std::end(metals::kMetals));
  const metals::ComplexIor gold = named_gold->ior;
  for (uint64_t k = 0; k < 1000; ++k) {
    const auto u = Uniform3(71, k);
    const Vec3 wi = SampleUniformSphere(u[0], u[1]);
    const Scattered s = SampleOne(*model, wi, Uniform3(72, k));
    if (wi.z <= 0) {  // one-sided
      EXPECT_EQ(s.flags, uint32_t(kScatterNone));
      EXPECT_EQ(s.pdf, 0.0f);
      ExpectVecNear(s.weight, Vec3(), 0, "weight below");
      continue;
    }
    EXPECT_EQ(s.wo.x, -wi.x);
    EXPECT_EQ(s.wo.y, -wi.y);
    EXPECT_EQ(s.wo.z, wi.z);
    EXPECT_EQ(s.pdf, 1.0f);
    EXPECT_EQ(s.flags, uint32_t(kScatterReflect | kScatterDelta));
    ExpectVecNear(s.weight, specular * mf::FresnelConductor(wi.z, gold.eta, gold.k), 1e-6f,
                  "weight");
    ExpectVecNear(EvaluateOne(*model, wi, s.wo), Vec3(), 0, "Evaluate");
    EXPECT_EQ(PdfOne(*model, wi, s.wo), 0.0f);
  }
  // The default is Mitsuba's perfect mirror; eta and k give the index.
  const Vec3 wi = DirectionAt(0.3, 0.2);
  ExpectVecNear(SampleOne(*Make("conductor"), wi, {0.5f, 0.5f, 0.5f}).weight, Vec3(1, 1, 1),
                1e-6f, "default");
  const auto custom = Make("conductor", Props({{"eta", Rgb{Vec3(0.2f, 0.9f, 1.1f)}},
                                               {"k", Rgb{Vec3(3.9f, 2.4f, 2.1f)}}}));
  ExpectVecNear(SampleOne(*custom, wi, {0.5f, 0.5f, 0.5f}).weight,
                mf::FresnelConductor(wi.z, Vec3(0.2f, 0.9f, 1.1f), Vec3(3.9f, 2.4f, 2.1f)),
                1e-6f, "eta and k");
  EXPECT_EQ(SampleOne(*model, wi, {0.5f, 0.5f, 0.5f}, kScatterRefract | kScatterDelta).flags,
            uint32_t(kScatterNone));
  EXPECT_EQ(SampleOne(*model, wi, {0.5f, 0.5f, 0.5f}, kScatterReflect | kScatterGlossy).flags,
            uint32_t(kScatterNone));
}

// --- roughconductor ----------------------------------------------------------

TEST_F(RoughConductorTest, SamplesFollowPdf) {
  const std::vector<Properties> variants = {
      Props({{"alpha", 0.15}}), Props({{"alpha", 0.5}}),
      Props({{"alpha_u", 0.1}, {"alpha_v", 0.4}, {"material", std::string("Cu")}}),
      Props({{"alpha", 0.3}, {"distribution", std::string("beckmann")}}),
      Props({{"alpha_u", 0.1}, {"alpha_v", 0.4}, {"distribution", std::string("beckmann")}})};
  for (const Properties& props : variants) {
    const auto model = Make("roughconductor", props);
    for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.5, 1.0), DirectionAt(0.1, -2.0)})
      EXPECT_TRUE(SamplesFollowPdf(*model, wi, 200000, 81)) << "variant " << &props - &variants[0] << ", wi " << Describe(wi);
  }
}

TEST_F(RoughConductorTest, SampleAgreesWithPdfAndEvaluate) {
  for (double alpha : {0.01, 0.1, 0.6}) {
    const auto model =
        Make("roughconductor", Props({{"alpha", alpha}, {"material", std::string("Au")}}));
    for (Vec3 wi : Above()) {
      const int produced = ExpectSampleAgreesWithPdfAndEvaluate(*model, wi, 2000, 82, kRadiance,
                                                                "alpha " + std::to_string(alpha));
      EXPECT_GT(produced, 2000 / 2) << "alpha " << alpha << ", wi " << Describe(wi);
    }
    // No sample from below: the conductor is one-sided.
    for (const Scattered& s : SampleMany(*model, DirectionAt(-0.5, 0.3), 100, 83))
      EXPECT_EQ(s.flags, uint32_t(kScatterNone));
  }
}

TEST_F(RoughConductorTest, PdfIntegratesToTheRateOfSamples) {
  ExpectPdfIntegratesToTheRateOfSamples(
      "roughconductor", {Vec3(0, 0, 1), DirectionAt(0.5, 1.0), DirectionAt(0.1, -2.0)}, 84);
}

TEST_F(RoughConductorTest, IsReciprocalAndOneSided) {
  const auto model = Make("roughconductor", Props({{"alpha_u", 0.2},
                                                   {"alpha_v", 0.5},
                                                   {"material", std::string("Cu")}}));
  ExpectReciprocalAndOneSided(*model, 85);
}

TEST_F(RoughConductorTest, ConservesEnergy) {
  const Properties mirror = Props({{"eta", 0.0}, {"k", 1.0}, {"specular_reflectance", 1.0}});
  for (const std::string distribution : {"ggx", "beckmann"})
  for (double alpha : {0.2, 0.5, 1.0}) {
    Properties props = mirror;
    props.Set("alpha", alpha);
    props.Set("distribution", distribution);
    const auto model = Make("roughconductor", props);
    for (Vec3 wi : Above()) {
      const Vec3 quadrature = IntegrateOverSphere(*model, wi).albedo;
      const MeanWithError sampled = MeanWeight(SampleMany(*model, wi, 50000, 87));
      const std::string where = distribution + " alpha " + std::to_string(alpha) + ", wi " + Describe(wi);
      EXPECT_LE(quadrature.x, 1.0f + 2e-3f) << where;
      EXPECT_LE(sampled.mean.x, 1.0f) << where;  // every weight F G2/G1 is ≤ 1
      EXPECT_NEAR(sampled.mean.x, quadrature.x, 5 * sampled.standard_error.x + 3e-3f) << where;
    }
  }
  // A nearly smooth perfect mirror loses almost nothing to masking.
  Properties smooth = mirror;
  smooth.Set("alpha", 0.01);
  const auto model = Make("roughconductor", smooth);
  for (Vec3 wi : Above()) {
    const MeanWithError sampled = MeanWeight(SampleMany(*model, wi, 20000, 88));
    EXPECT_GT(sampled.mean.x, wi.z > 0.1f ? 0.995f : 0.97f) << "wi " << Describe(wi);
    EXPECT_LE(sampled.mean.x, 1.0f) << "wi " << Describe(wi);
  }
}

TEST_F(RoughConductorTest, ConvergesToConductorAsAlphaVanishes) {
  const Properties gold = Props({{"material", std::string("Au")}});
  Properties rough = gold;
  rough.Set("alpha", 0.001);
  const auto model = Make("roughconductor", rough);
  const auto smooth = Make("conductor", gold);
  for (Vec3 wi : Above()) {
    const Vec3 expected = SampleOne(*smooth, wi, {0.5f, 0.5f, 0.5f}).weight;
    const std::vector<Scattered> samples = SampleMany(*model, wi, 5000, 89);
    // GGX's tails are long: P(tan θm > t) = α² / (α² + t²), so about 1% of
    // the normals lie beyond 10α, and deflect wo by more than 20α.
    int near_mirror = 0;
    for (const Scattered& s : samples)
      near_mirror += s.pdf > 0 && Length(s.wo - Reflect(wi)) < 0.02f;
    EXPECT_GT(near_mirror, 0.97 * 5000) << "wi " << Describe(wi);
    ExpectVecNear(MeanWeight(samples).mean, expected, wi.z > 0.1f ? 2e-3f : 2e-2f,
                  "albedo at wi " + Describe(wi));
  }
}

// --- roughdielectric ---------------------------------------------------------

TEST_F(RoughDielectricTest, SamplesFollowPdf) {
  const std::vector<Properties> variants = {
      Props({{"alpha", 0.15}}), Props({{"alpha", 0.5}}),
      Props({{"alpha_u", 0.1}, {"alpha_v", 0.3}, {"int_ior", 1.33}}),
      Props({{"alpha", 0.25}, {"distribution", std::string("beckmann")}})};
  for (const Properties& props : variants) {
    const auto model = Make("roughdielectric", props);
    for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.3, 1.0), DirectionAt(0.08, 2.5),
                    DirectionAt(-0.9, -2.0), DirectionAt(-0.6, 0.5)})
      EXPECT_TRUE(SamplesFollowPdf(*model, wi, 200000, 91)) << "wi " << Describe(wi);
  }
}

TEST_F(RoughDielectricTest, SampleAgreesWithPdfAndEvaluate) {
  for (double alpha : {0.01, 0.1, 0.6}) {
    const auto model = Make("roughdielectric", Props({{"alpha", alpha}}));
    for (TransportMode mode : {kRadiance, kImportance})
      for (Vec3 wi : BothSides()) {
        const int produced = ExpectSampleAgreesWithPdfAndEvaluate(
            *model, wi, 2000, 92, mode, "alpha " + std::to_string(alpha));
        EXPECT_GT(produced, 2000 / 2) << "alpha " << alpha << ", wi " << Describe(wi);
      }
  }
}

TEST_F(RoughDielectricTest, PdfIntegratesToTheRateOfSamples) {
  ExpectPdfIntegratesToTheRateOfSamples("roughdielectric",
                                        {Vec3(0, 0, 1), DirectionAt(0.2, 1.0),
                                         DirectionAt(-0.9, 0.3), DirectionAt(-0.4, -1.0)},
                                        93);
}

TEST_F(RoughDielectricTest, GeneralisedReciprocity) {
  // Reflection: f(a, b) = f(b, a). Refraction of radiance: f(a, b) / η_a²
  // = f(b, a) / η_b², η the index on each direction's side; importance is
  // the adjoint: f_importance(a, b) = f_radiance(b, a).
  const auto model = Make("roughdielectric", Props({{"alpha_u", 0.3}, {"alpha_v", 0.15}}));
  int refractions = 0;
  for (uint64_t k = 0; k < 4000; ++k) {
    const auto u = Uniform3(94, k), v = Uniform3(95, k);
    const Vec3 a = SampleUniformSphere(u[0], u[1]), b = SampleUniformSphere(v[0], v[1]);
    const float f_ab = EvaluateOne(*model, a, b).x, f_ba = EvaluateOne(*model, b, a).x;
    const std::string where = "a " + Describe(a) + ", b " + Describe(b);
    if (a.z * b.z > 0) {
      EXPECT_NEAR(f_ab, f_ba, 1e-4f * std::max(1.0f, f_ab)) << where;
      continue;
    }
    refractions += f_ab > 0;
    const float eta_a = a.z > 0 ? 1.0f : kEta, eta_b = b.z > 0 ? 1.0f : kEta;
    EXPECT_NEAR(f_ab / (eta_a * eta_a), f_ba / (eta_b * eta_b), 1e-4f * std::max(1.0f, f_ab))
        << where;
    EXPECT_NEAR(EvaluateOne(*model, a, b, kImportance).x, f_ba, 1e-4f * std::max(1.0f, f_ba))
        << where;
  }
  EXPECT_GT(refractions, 300);
}

TEST_F(RoughDielectricTest, ConservesEnergy) {
  // Importance weights are G2/G1 ≤ 1: the energy that scatters once.
  // Radiance weights differ from them by 1/η² on refraction only.
  for (double alpha : {0.05, 0.3, 1.0}) {
    const auto model = Make("roughdielectric", Props({{"alpha", alpha}}));
    for (Vec3 wi : BothSides()) {
      const std::string where = "alpha " + std::to_string(alpha) + ", wi " + Describe(wi);
      const std::vector<Scattered> importance = SampleMany(*model, wi, 20000, 96, 0, kImportance);
      const std::vector<Scattered> radiance = SampleMany(*model, wi, 20000, 96, 0, kRadiance);
      for (size_t k = 0; k < importance.size(); ++k) {
        EXPECT_LE(importance[k].weight.x, 1.0f + 1e-4f) << where;
        const float eta = RefractedEta(wi);
        const float expected = importance[k].flags & kScatterRefract
                                   ? importance[k].weight.x / (eta * eta)
                                   : importance[k].weight.x;
        EXPECT_NEAR(radiance[k].weight.x, expected, 1e-4f) << where;
      }
      const MeanWithError energy = MeanWeight(importance);
      EXPECT_LE(energy.mean.x, 1.0f) << where;
      // Light at normal incidence on a smooth-ish interface is not masked.
      if (alpha == 0.05 && std::abs(wi.z) > 0.9f) {
        EXPECT_GT(energy.mean.x, 0.995f) << where;
      }
    }
  }
}

TEST_F(RoughDielectricTest, ConvergesToDielectricAsAlphaVanishes) {
  // Lobe fractions are the Fresnel factor of dielectric.cc, directions
  // those of the mirror and of Snell's law, weights 1 and 1/η².
  // (GGX's long tails: a few normals lie far from +z, so the directions
  // are checked for most samples, the weights on average.)
  const auto model = Make("roughdielectric", Props({{"alpha", 0.001}}));
  constexpr int kCount = 10000;
  for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.8, 0.3), DirectionAt(0.3, 1.0),
                  DirectionAt(-1.0, 0.0), DirectionAt(-0.9, 2.0), DirectionAt(-0.85, -1.0),
                  DirectionAt(-0.2, 0.5)}) {
    const std::string where = "wi " + Describe(wi);
    const float fresnel = FresnelDielectric(wi.z, kEta);
    const float eta = RefractedEta(wi);
    Vec3 refracted;
    const bool can_refract = Refract(wi, kEta, &refracted);
    int reflected = 0, produced = 0, on_course = 0;
    double reflect_weight = 0, refract_weight = 0;
    for (const Scattered& s : SampleMany(*model, wi, kCount, 97, 0, kRadiance, true)) {
      if (!(s.pdf > 0)) continue;
      ++produced;
      if (s.flags & kScatterReflect) {
        ++reflected;
        on_course += Length(s.wo - Reflect(wi)) < 0.02f;
        reflect_weight += s.weight.x;
      } else {
        ASSERT_TRUE(can_refract) << where;
        on_course += Length(s.wo - refracted) < 0.02f;
        refract_weight += s.weight.x;
      }
    }
    EXPECT_GT(produced, 0.999 * kCount) << where;
    EXPECT_GT(on_course, 0.97 * kCount) << where;
    EXPECT_NEAR(reflected / double(kCount), fresnel, 5e-3) << where;
    if (reflected > 0) {
      EXPECT_NEAR(reflect_weight / reflected, 1.0, 2e-3) << where;
    }
    if (produced > reflected) {
      EXPECT_NEAR(refract_weight / (produced - reflected), 1.0 / (eta * eta), 2e-3) << where;
    }
  }
}

TEST_F(RoughDielectricTest, AllowedLobesSplitTheAlbedo) {
  // Each lobe alone carries its Fresnel factor: the mean weights of the
  // reflection alone and of the refraction alone add up to that of both.
  const auto model = Make("roughdielectric", Props({{"alpha", 0.3}}));
  constexpr uint32_t kReflect = kScatterReflect | kScatterGlossy;
  constexpr uint32_t kRefract = kScatterRefract | kScatterGlossy;
  for (Vec3 wi : {DirectionAt(0.9, 0.3), DirectionAt(0.3, 1.0), DirectionAt(-0.8, 2.0)}) {
    const std::vector<Scattered> reflected =
        SampleMany(*model, wi, 40000, 98, kReflect, kImportance);
    const std::vector<Scattered> refracted =
        SampleMany(*model, wi, 40000, 99, kRefract, kImportance);
    for (const Scattered& s : reflected)
      EXPECT_TRUE(s.flags == kReflect || s.flags == kScatterNone);
    for (const Scattered& s : refracted)
      EXPECT_TRUE(s.flags == kRefract || s.flags == kScatterNone);
    const MeanWithError r = MeanWeight(reflected), t = MeanWeight(refracted);
    const MeanWithError both = MeanWeight(SampleMany(*model, wi, 40000, 100, 0, kImportance));
    const float error = r.standard_error.x + t.standard_error.x + both.standard_error.x;
    EXPECT_NEAR(r.mean.x + t.mean.x, both.mean.x, 4 * error) << "wi " << Describe(wi);
    EXPECT_EQ(SampleOne(*model, wi, {0.5f, 0.5f, 0.5f}, kScatterReflect | kScatterDelta).flags,
              uint32_t(kScatterNone));
  }
}

// --- plastic -------------------------------------------------------------------

TEST_F(PlasticTest, SpecularLobeIsExactAndDiffuseFollowsPdf) {
  const auto model = Make("plastic", Props({{"diffuse_reflectance", Rgb{Vec3(0.2f, 0.5f, 0.8f)}}}));
  constexpr uint32_t kSpecular = kScatterReflect | kScatterDelta;
  for (Vec3 wi : Above()) {
    const float fresnel = FresnelDielectric(wi.z, kEta);
    // Mitsuba's lobe odds: F s against (1 - F)(1 - s), s = 1 / (1 + mean ρ).
    const float s = 1.0f / (1.0f + 0.5f);
    const float p_specular = fresnel * s / (fresnel * s + (1 - fresnel) * (1 - s));
    constexpr int kCount = 10000;
    int specular = 0;
    for (const Scattered& sample : SampleMany(*model, wi, kCount, 101, 0, kRadiance, true)) {
      ASSERT_GT(sample.pdf, 0.0f);
      if (sample.flags != kSpecular) continue;
      ++specular;
      EXPECT_EQ(sample.wo.x, -wi.x);
      EXPECT_EQ(sample.wo.y, -wi.y);
      EXPECT_EQ(sample.wo.z, wi.z);
      EXPECT_NEAR(sample.pdf, p_specular, 1e-5f);
      ExpectVecNear(sample.weight, Vec3(1, 1, 1) * (fresnel / p_specular), 1e-5f, "specular");
    }
    EXPECT_NEAR(specular / double(kCount), p_specular, 1.0 / kCount) << "wi " << Describe(wi);
    ExpectSampleAgreesWithPdfAndEvaluate(*model, wi, 2000, 102, kRadiance, "plastic");
  }
  for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.4, 1.0), DirectionAt(0.1, -2.0)})
    EXPECT_TRUE(SamplesFollowPdf(*model, wi, 200000, 103)) << "wi " << Describe(wi);
}

TEST_F(PlasticTest, AlbedoIsFresnelPlusTransmittedDiffuse) {
  // With nonlinear = false, the albedo is F + ρ (1 - F): the light the
  // coating lets in comes out, ρ of it.
  for (Vec3 rho : {Vec3(1, 1, 1), Vec3(0.2f, 0.5f, 0.8f)})
    for (double int_ior : {1.49, 1.9}) {
      const auto model =
          Make("plastic", Props({{"diffuse_reflectance", Rgb{rho}}, {"int_ior", int_ior}}));
      const float eta = float(int_ior / 1.000277);
      for (Vec3 wi : Above()) {
        const float fresnel = FresnelDielectric(wi.z, eta);
        const Vec3 diffuse = IntegrateOverSphere(*model, wi).albedo;
        ExpectVecNear(diffuse + Vec3(fresnel, fresnel, fresnel),
                      Vec3(fresnel, fresnel, fresnel) + rho * (1 - fresnel), 1e-3f,
                      "albedo at wi " + Describe(wi));
        const MeanWithError sampled = MeanWeight(SampleMany(*model, wi, 20000, 104));
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(sampled.mean[c], fresnel + rho[c] * (1 - fresnel),
                      5 * sampled.standard_error[c] + 1e-3f)
              << "wi " << Describe(wi);
      }
    }
  // nonlinear = true darkens it.
  const auto nonlinear =
      Make("plastic", Props({{"diffuse_reflectance", 0.5}, {"nonlinear", true}}));
  const Vec3 darker = IntegrateOverSphere(*nonlinear, Vec3(0, 0, 1)).albedo;
  const float fresnel = FresnelDielectric(1.0f, kEta);
  EXPECT_LT(darker.x, 0.5f * (1 - fresnel));
  EXPECT_GT(darker.x, 0.25f * (1 - fresnel));
}

TEST_F(PlasticTest, IsReciprocalAndOneSided) {
  const auto model = Make("plastic");
  for (uint64_t k = 0; k < 2000; ++k) {
    const auto u = Uniform3(105, k), v = Uniform3(106, k);
    const Vec3 a = SampleUniformSphere(u[0], u[1]), b = SampleUniformSphere(v[0], v[1]);
    ExpectVecNear(EvaluateOne(*model, a, b), EvaluateOne(*model, b, a), 1e-6f, "f(a, b)");
    EXPECT_EQ(PdfOne(*model, a, b) > 0, a.z > 0 && b.z > 0);
  }
  for (const Scattered& s : SampleMany(*model, DirectionAt(-0.5, 0.3), 100, 107))
    EXPECT_EQ(s.flags, uint32_t(kScatterNone));
  // One lobe allowed: that lobe, always.
  const Vec3 wi = DirectionAt(0.6, 0.2);
  for (const Scattered& s :
       SampleMany(*model, wi, 100, 108, kScatterReflect | kScatterDiffuse)) {
    EXPECT_EQ(s.flags, uint32_t(kScatterReflect | kScatterDiffuse));
    EXPECT_NEAR(s.pdf, CosineHemispherePdf(s.wo.z), 1e-6f);
  }
  const Scattered specular =
      SampleOne(*model, wi, {0.9f, 0.5f, 0.5f}, kScatterReflect | kScatterDelta);
  EXPECT_EQ(specular.flags, uint32_t(kScatterReflect | kScatterDelta));
  EXPECT_EQ(specular.pdf, 1.0f);
  EXPECT_NEAR(specular.weight.x, FresnelDielectric(wi.z, kEta), 1e-6f);
}

// --- pplastic --------------------------------------------------------------------

TEST_F(PPlasticTest, SamplesFollowPdf) {
  for (const Properties& props : {Props({{"alpha", 0.15}}), Props({{"alpha_u", 0.1}, {"alpha_v", 0.5}})}) {
    const auto model = Make("pplastic", props);
    for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.5, 1.0), DirectionAt(0.1, -2.0)})
      EXPECT_TRUE(SamplesFollowPdf(*model, wi, 200000, 121)) << "wi " << Describe(wi);
  }
}

TEST_F(PPlasticTest, SampleAgreesWithPdfAndEvaluate) {
  for (double alpha : {0.01, 0.1, 0.6}) {
    const auto model =
        Make("pplastic", Props({{"alpha", alpha}, {"diffuse_reflectance", Rgb{Vec3(0.1f, 0.4f, 0.9f)}}}));
    for (Vec3 wi : Above()) {
      const int produced =
          ExpectSampleAgreesWithPdfAndEvaluate(*model, wi, 2000, 122, kRadiance, "alpha " + std::to_string(alpha));
      EXPECT_GT(produced, 2000 / 2) << "alpha " << alpha << ", wi " << Describe(wi);
    }
  }
}

TEST_F(PPlasticTest, PdfIntegratesToTheRateOfSamples) {
  ExpectPdfIntegratesToTheRateOfSamples("pplastic", {Vec3(0, 0, 1), DirectionAt(0.5, 1.0), DirectionAt(0.1, -2.0)},
                                        123);
}

TEST_F(PPlasticTest, IsReciprocalAndOneSided) {
  ExpectReciprocalAndOneSided(*Make("pplastic", Props({{"alpha", 0.3}})), 124);
}

// The coating and the base reflect apart: the coating as roughplastic's
// (the same rough dielectric), the base through the smooth interface's
// Fresnel transmittance in and out, and nothing else.
TEST_F(PPlasticTest, IsTheCoatingsReflectionPlusTheBaseSeenThroughTheInterface) {
  const Vec3 rho(0.2f, 0.5f, 0.8f);
  const auto coating_only = Make("pplastic", Props({{"alpha", 0.25}, {"diffuse_reflectance", 0.0}}));
  const auto rough_coating = Make("roughplastic", Props({{"alpha", 0.25}, {"diffuse_reflectance", 0.0}}));
  const auto base_only = Make("pplastic", Props({{"diffuse_reflectance", Rgb{rho}}, {"specular_reflectance", 0.0}}));
  const auto both = Make("pplastic", Props({{"alpha", 0.25}, {"diffuse_reflectance", Rgb{rho}}}));
  for (uint64_t k = 0; k < 500; ++k) {
    const auto u = Uniform3(125, k), v = Uniform3(126, k);
    const Vec3 wi = SampleUniformHemisphere(u[0], u[1]), wo = SampleUniformHemisphere(v[0], v[1]);
    const Vec3 coating = EvaluateOne(*coating_only, wi, wo);
    ExpectVecNear(coating, EvaluateOne(*rough_coating, wi, wo), 1e-5f, "coating " + Describe(wi) + Describe(wo));
    const float through = (1 - FresnelDielectric(wi.z, kEta)) * (1 - FresnelDielectric(wo.z, kEta));
    const Vec3 base = rho * (through * kInvPi);
    ExpectVecNear(EvaluateOne(*base_only, wi, wo), base, 1e-5f, "base " + Describe(wi) + Describe(wo));
    ExpectVecNear(EvaluateOne(*both, wi, wo), coating + base, 1e-5f, "both " + Describe(wi) + Describe(wo));
  }
  // A white base under a smooth coating reflects less than all: nothing the
  // interface reflects back inside comes out again.
  const auto white = Make("pplastic", Props({{"alpha", 0.05}, {"diffuse_reflectance", 1.0}}));
  for (Vec3 wi : Above()) {
    const SphereIntegrals sums = IntegrateOverSphere(*white, wi);
    EXPECT_LT(sums.albedo.x, 1.0f) << Describe(wi);
    EXPECT_GT(sums.albedo.x, 0.5f) << Describe(wi);
  }
}

// --- roughplastic ----------------------------------------------------------------

TEST_F(RoughPlasticTest, SamplesFollowPdf) {
  for (double alpha : {0.15, 0.5}) {
    const auto model = Make("roughplastic", Props({{"alpha", alpha}}));
    for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.5, 1.0), DirectionAt(0.1, -2.0)})
      EXPECT_TRUE(SamplesFollowPdf(*model, wi, 200000, 111))
          << "alpha " << alpha << ", wi " << Describe(wi);
  }
}

TEST_F(RoughPlasticTest, SampleAgreesWithPdfAndEvaluate) {
  for (double alpha : {0.01, 0.1, 0.6}) {
    const auto model = Make("roughplastic",
                            Props({{"alpha", alpha},
                                   {"diffuse_reflectance", Rgb{Vec3(0.1f, 0.4f, 0.9f)}}}));
    for (Vec3 wi : Above()) {
      const int produced = ExpectSampleAgreesWithPdfAndEvaluate(*model, wi, 2000, 112, kRadiance,
                                                                "alpha " + std::to_string(alpha));
      EXPECT_GT(produced, 2000 / 2) << "alpha " << alpha << ", wi " << Describe(wi);
    }
  }
}

TEST_F(RoughPlasticTest, PdfIntegratesToTheRateOfSamples) {
  ExpectPdfIntegratesToTheRateOfSamples(
      "roughplastic", {Vec3(0, 0, 1), DirectionAt(0.5, 1.0), DirectionAt(0.1, -2.0)}, 113);
}

TEST_F(RoughPlasticTest, IsReciprocalAndOneSided) {
  const auto model = Make("roughplastic", Props({{"alpha", 0.3}}));
  ExpectReciprocalAndOneSided(*model, 114);
}

TEST_F(RoughPlasticTest, ConservesEnergy) {
  // As Mitsuba's, the model loses energy as the coating roughens: the
  // internal reflectance r̄ leaves out the light the rough inside masks,
  // which 1 / (1 - r̄) thus counts as leaving, while the transmittance t on
  // the way out lets less through. A white base's albedo falls below 1.
  std::vector<double> white_albedo;  // at normal incidence, by roughness
  for (double alpha : {0.02, 0.2, 0.5, 1.0})
    for (double rho : {1.0, 0.5}) {
      const auto model =
          Make("roughplastic", Props({{"alpha", alpha}, {"diffuse_reflectance", rho}}));
      for (Vec3 wi : Above()) {
        const std::string where = "alpha " + std::to_string(alpha) + ", rho " +
                                  std::to_string(rho) + ", wi " + Describe(wi);
        const MeanWithError sampled = MeanWeight(SampleMany(*model, wi, 20000, 116));
        EXPECT_LE(sampled.mean.x, 1.0f + 4 * sampled.standard_error.x) << where;
        if (rho == 1.0 && wi.z == 1.0f) white_albedo.push_back(sampled.mean.x);
        if (alpha < 0.1) continue;  // a lobe too sharp for the quadrature grid
        const Vec3 quadrature = IntegrateOverSphere(*model, wi).albedo;
        EXPECT_LE(quadrature.x, 1.0f + 3e-3f) << where;
        EXPECT_NEAR(sampled.mean.x, quadrature.x, 5 * sampled.standard_error.x + 3e-3f) << where;
      }
    }
  ASSERT_EQ(white_albedo.size(), 4u);
  EXPECT_GT(white_albedo[0], 0.97);
  for (size_t k = 1; k < white_albedo.size(); ++k)
    EXPECT_LT(white_albedo[k], white_albedo[k - 1]) << "alpha index " << k;
}

TEST_F(RoughPlasticTest, ConvergesToPlasticAsAlphaVanishes) {
  const Vec3 rho(0.2f, 0.5f, 0.8f);
  const auto rough =
      Make("roughplastic", Props({{"alpha", 0.001}, {"diffuse_reflectance", Rgb{rho}}}));
  const auto smooth = Make("plastic", Props({{"diffuse_reflectance", Rgb{rho}}}));
  for (Vec3 wi : Above()) {
    const MeanWithError a = MeanWeight(SampleMany(*rough, wi, 40000, 117));
    const MeanWithError b = MeanWeight(SampleMany(*smooth, wi, 40000, 118));
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(a.mean[c], b.mean[c],
                  5 * (a.standard_error[c] + b.standard_error[c]) + (wi.z > 0.1f ? 5e-3f : 2e-2f))
          << "wi " << Describe(wi) << " channel " << c;
    // The diffuse lobes agree value for value.
    for (Vec3 wo : {DirectionAt(0.9, 1.0), DirectionAt(0.4, -2.0)})
      ExpectVecNear(EvaluateOne(*rough, wi, wo), EvaluateOne(*smooth, wi, wo), 1e-2f,
                    "diffuse at wi " + Describe(wi) + ", wo " + Describe(wo));
  }
}

// --- thindielectric ----------------------------------------------------------

TEST_F(ThinDielectricTest, ProbabilitiesAreTheSlabsReflectanceAndTransmittance) {
  const auto model = Make("thindielectric");
  constexpr float kEta = float(1.5046 / 1.000277);
  constexpr uint32_t kReflect = kScatterReflect | kScatterDelta;
  constexpr uint32_t kTransmit = kScatterRefract | kScatterDelta;
  constexpr int kCount = 10000;
  for (Vec3 wi : BothSides()) {
    const float fresnel = FresnelDielectric(std::abs(wi.z), kEta);
    const float reflectance = 2 * fresnel / (1 + fresnel);
    int reflected = 0;
    for (TransportMode mode : {kRadiance, kImportance})
      for (const Scattered& s : SampleMany(*model, wi, kCount, 121, 0, mode, true)) {
        ExpectVecNear(s.weight, Vec3(1, 1, 1), 1e-6f, "weight");
        ExpectVecNear(EvaluateOne(*model, wi, s.wo), Vec3(), 0, "Evaluate");
        EXPECT_EQ(PdfOne(*model, wi, s.wo), 0.0f);
        if (s.flags == kReflect) {
          reflected += mode == kRadiance;
          EXPECT_EQ(s.wo.x, -wi.x);
          EXPECT_EQ(s.wo.y, -wi.y);
          EXPECT_EQ(s.wo.z, wi.z);
          EXPECT_NEAR(s.pdf, reflectance, 1e-6f);
        } else {
          ASSERT_EQ(s.flags, kTransmit);
          EXPECT_EQ(s.wo.x, -wi.x);
          EXPECT_EQ(s.wo.y, -wi.y);
          EXPECT_EQ(s.wo.z, -wi.z);
          EXPECT_NEAR(s.pdf, 1 - reflectance, 1e-6f);
        }
      }
    EXPECT_NEAR(reflected / double(kCount), reflectance, 1.0 / kCount) << "wi " << Describe(wi);
    // One lobe allowed: its factor in the weight.
    const Scattered r = SampleOne(*model, wi, {0.999f, 0.5f, 0.5f}, kReflect);
    EXPECT_EQ(r.flags, kReflect);
    EXPECT_EQ(r.pdf, 1.0f);
    EXPECT_NEAR(r.weight.x, reflectance, 1e-6f);
    const Scattered t = SampleOne(*model, wi, {0.001f, 0.5f, 0.5f}, kTransmit);
    EXPECT_EQ(t.flags, kTransmit);
    EXPECT_EQ(t.pdf, 1.0f);
    EXPECT_NEAR(t.weight.x, 1 - reflectance, 1e-6f);
    EXPECT_EQ(SampleOne(*model, wi, {0.5f, 0.5f, 0.5f}, kScatterReflect | kScatterGlossy).flags,
              uint32_t(kScatterNone));
  }
  // Matched indices: an invisible pane.
  const auto invisible = Make("thindielectric", Props({{"int_ior", 1.2}, {"ext_ior", 1.2}}));
  const Scattered s = SampleOne(*invisible, DirectionAt(0.3, 1.0), {0.5f, 0.5f, 0.5f});
  EXPECT_EQ(s.flags, kTransmit);
  ExpectVecNear(s.wo, -DirectionAt(0.3, 1.0), 0, "straight through");
}

// --- diffusetransmission -----------------------------------------------------

TEST_F(DiffuseTransmissionTest, SamplesFollowPdf) {
  const auto model = Make("diffusetransmission",
                          Props({{"reflectance", Rgb{Vec3(0.6f, 0.2f, 0.1f)}},
                                 {"transmittance", 0.3}}));
  for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.05, 1.0), DirectionAt(-0.7, -2.0)})
    EXPECT_TRUE(SamplesFollowPdf(*model, wi, 200000, 131)) << "wi " << Describe(wi);
}

TEST_F(DiffuseTransmissionTest, SampleAgreesWithPdfEvaluateAndAlbedo) {
  const Vec3 reflectance(0.6f, 0.2f, 0.1f), transmittance(0.3f, 0.5f, 0.0f);
  const auto model = Make("diffusetransmission", Props({{"reflectance", Rgb{reflectance}},
                                                        {"transmittance", Rgb{transmittance}}}));
  for (Vec3 wi : BothSides()) {
    for (TransportMode mode : {kRadiance, kImportance})
      EXPECT_GE(ExpectSampleAgreesWithPdfAndEvaluate(*model, wi, 2000, 132, mode,
                                                     "diffusetransmission"),
                1990);
    const SphereIntegrals integrals = IntegrateOverSphere(*model, wi);
    EXPECT_NEAR(integrals.pdf, 1.0, 1e-3) << "wi " << Describe(wi);
    ExpectVecNear(integrals.albedo, reflectance + transmittance, 1e-3f,
                  "albedo at wi " + Describe(wi));
    ExpectVecNear(MeanWeight(SampleMany(*model, wi, 20000, 133)).mean,
                  reflectance + transmittance, 2e-2f, "sampled albedo at wi " + Describe(wi));
  }
  // Reciprocal and two-sided.
  for (uint64_t k = 0; k < 500; ++k) {
    const auto u = Uniform3(134, k), v = Uniform3(135, k);
    const Vec3 a = SampleUniformSphere(u[0], u[1]), b = SampleUniformSphere(v[0], v[1]);
    ExpectVecNear(EvaluateOne(*model, a, b), EvaluateOne(*model, b, a), 0, "f(a, b)");
    ExpectVecNear(EvaluateOne(*model, -a, -b), EvaluateOne(*model, a, b), 0, "back side");
  }
  // One lobe allowed: that lobe, with its colour as the weight.
  const Vec3 wi = DirectionAt(0.5, 0.5);
  for (const Scattered& s : SampleMany(*model, wi, 200, 136, kScatterRefract | kScatterDiffuse)) {
    EXPECT_EQ(s.flags, uint32_t(kScatterRefract | kScatterDiffuse));
    EXPECT_LT(s.wo.z, 0.0f);
    ExpectVecNear(s.weight, transmittance, 1e-6f, "transmitted weight");
  }
}

// --- blend ---------------------------------------------------------------

class BlendTest : public MicrofacetTest {
 protected:
  std::unique_ptr<SurfaceModel> Blend(std::shared_ptr<const SurfaceModel> a, std::shared_ptr<const SurfaceModel> b,
                                      double weight) const {
    return Make("blend", Props({{"bsdf_0", a}, {"bsdf_1", b}, {"weight", weight}}));
  }
  std::shared_ptr<const SurfaceModel> Diffuse(double reflectance) const {
    return Make("lambertian", Props({{"reflectance", reflectance}}));
  }
};

TEST_F(BlendTest, IsTheWeightedSumOfItsModels) {
  const auto rough = std::shared_ptr<const SurfaceModel>(Make("roughconductor", Props({{"alpha", 0.3}})));
  const auto blend = Blend(Diffuse(0.8), rough, 0.25);
  EXPECT_EQ(blend->Lobes(), Diffuse(0.8)->Lobes() | rough->Lobes());
  for (uint64_t k = 0; k < 200; ++k) {
    const auto u = Uniform3(81, k);
    const Vec3 wi = SampleCosineHemisphere(u[0], u[1]), wo = SampleUniformHemisphere(u[2], u[0]);
    ExpectVecNear(EvaluateOne(*blend, wi, wo),
                  EvaluateOne(*Diffuse(0.8), wi, wo) * 0.75f + EvaluateOne(*rough, wi, wo) * 0.25f, 1e-5f, "value");
    EXPECT_NEAR(PdfOne(*blend, wi, wo), 0.75f * PdfOne(*Diffuse(0.8), wi, wo) + 0.25f * PdfOne(*rough, wi, wo),
                1e-5f * (1 + PdfOne(*blend, wi, wo)));
  }
}

TEST_F(BlendTest, SamplesFollowTheBlendedDensity) {
  const auto rough = std::shared_ptr<const SurfaceModel>(Make("roughconductor", Props({{"alpha", 0.2}})));
  const auto blend = Blend(Diffuse(0.5), rough, 0.6);
  for (const Vec3 wi : {Vec3(0, 0, 1), Normalize(Vec3(0.6f, 0.1f, 0.4f))}) {
    EXPECT_GT(ExpectSampleAgreesWithPdfAndEvaluate(*blend, wi, 2000, 82, TransportMode::kRadiance, "blend"), 1500);
    std::vector<Vec3> directions;
    for (const Scattered& s : SampleMany(*blend, wi, 100000, 83))
      if (s.pdf > 0) directions.push_back(s.wo);
    EXPECT_TRUE(DirectionsFollowPdf(*blend, wi, directions, 100000)) << Describe(wi);
  }
}

TEST_F(BlendTest, AlbedoIsTheWeightedAlbedoWithDeltaLobes) {
  // A smooth mirror (delta) and a diffuse surface: the mean weight of
  // Sample is 0.3 · 1 + 0.7 · 0.5 at every wi.
  const auto mirror = std::shared_ptr<const SurfaceModel>(Make("conductor"));
  const auto blend = Blend(Diffuse(0.5), mirror, 0.3);
  for (const Vec3 wi : {Vec3(0, 0, 1), Normalize(Vec3(0.7f, 0.0f, 0.3f))}) {
    const MeanWithError albedo = MeanWeight(SampleMany(*blend, wi, 40000, 84));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(albedo.mean[c], 0.65f, 4 * albedo.standard_error[c] + 1e-3f);
  }
}

TEST_F(BlendTest, RefusesAWeightOutsideTheUnitInterval) {
  EXPECT_NE(CreationError("blend", Props({{"bsdf_0", Diffuse(0.5)}, {"bsdf_1", Diffuse(0.5)}, {"weight", 1.5}}))
                .find("'weight'"),
            std::string::npos);
  EXPECT_NE(CreationError("blend", Props({{"bsdf_0", Diffuse(0.5)}})).find("'bsdf_1'"), std::string::npos);
}

}  // namespace
}  // namespace yarf
