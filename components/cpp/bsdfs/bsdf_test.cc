// Tests of the surface plugins (bsdfs/*.cc),
// loaded from the plugin folder through the registry as yarfd loads them:
// energy conservation, reciprocity, agreement of Sample with Pdf and
// Evaluate, the distribution of sampled directions (Pearson's χ² test),
// the delta lobes' directions and probabilities, and property checking.
// The fixture and the batch-call helpers are surface_test_support.h's.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "surface_test_support.h"
#include "yarf/surface.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

using namespace surface_testing;  // NOLINT: the shared helpers, in every test

// Incident directions from normal to near-grazing incidence, on both
// sides (the reflectors are two-sided).
std::vector<Vec3> IncidentDirections() {
  std::vector<Vec3> out;
  for (float cos_theta : {1.0f, 0.9f, 0.7f, 0.5f, 0.3f, 0.1f})
    for (float side : {1.0f, -1.0f})
      out.push_back(DirectionAt(side * cos_theta, 0.7 + 2.0 * cos_theta));
  return out;
}

// --- Directional albedo: ∫ f(wi, wo) |cos θo| dωo --------------------------

// By the midpoint rule over the sphere in (cos θo, φo), in one batch.
Vec3 AlbedoByQuadrature(const SurfaceModel& model, Vec3 wi) {
  constexpr int kRows = 1000, kCols = 400;
  const double dz = 2.0 / kRows, dphi = 2 * kPiDouble / kCols;
  std::vector<Vec3> wo;
  wo.reserve(size_t(kRows) * kCols);
  for (int i = 0; i < kRows; ++i)
    for (int j = 0; j < kCols; ++j)
      wo.push_back(DirectionAt(-1.0 + (i + 0.5) * dz, -kPiDouble + (j + 0.5) * dphi));
  const std::vector<Vec3> value = EvaluateBatch(model, wi, wo, TransportMode::kRadiance);
  double sum[3] = {0, 0, 0};
  for (size_t k = 0; k < wo.size(); ++k)
    for (int c = 0; c < 3; ++c) sum[c] += double(value[k][c]) * std::abs(wo[k].z);
  return Vec3(float(sum[0] * dz * dphi), float(sum[1] * dz * dphi), float(sum[2] * dz * dphi));
}

// --- Pearson's χ² test of sampled directions ---------------------------

// The expected count of a (cos θ, φ) cell is N ∫ pdf over it by
// Gauss–Legendre quadrature in cos θ and φ, one pdf call per node; a
// sample where the pdf is 0 fails at once.
testing::AssertionResult DirectionsFollowPdf(const std::vector<Vec3>& directions,
                                             int sample_count,
                                             const std::function<double(Vec3)>& pdf) {
  const double dz = 2.0 / kChiRows, dphi = 2 * kPiDouble / kChiCols;
  std::vector<double> expected(kChiRows * kChiCols, 0.0);
  for (int row = 0; row < kChiRows; ++row)
    for (int col = 0; col < kChiCols; ++col) {
      const double z_mid = -1.0 + (row + 0.5) * dz, phi_mid = -kPiDouble + (col + 0.5) * dphi;
      double sum = 0;
      for (int s = 0; s < 5; ++s)
        for (int t = 0; t < 5; ++t)
          sum += kGaussWeights[s] * kGaussWeights[t] *
                 pdf(DirectionAt(z_mid + 0.5 * dz * kGaussNodes[s],
                                 phi_mid + 0.5 * dphi * kGaussNodes[t]));
      expected[row * kChiCols + col] = sample_count * sum * (0.5 * dz) * (0.5 * dphi);
    }
  return CellsFollowExpected(directions, expected);
}

// --- Phong materials and the fixture -----------------------------------------

Properties PhongProperties(Vec3 diffuse, Vec3 specular, double exponent) {
  Properties props;
  props.Set("diffuse_reflectance", Rgb{diffuse});
  props.Set("specular_reflectance", Rgb{specular});
  props.Set("exponent", exponent);
  return props;
}

// Phong materials from matte to shiny, two at the energy limit kd + ks = 1.
std::vector<Properties> PhongVariants() {
  return {Properties(),
          PhongProperties(Vec3(0.5f, 0.5f, 0.5f), Vec3(0.5f, 0.5f, 0.5f), 30.0),
          PhongProperties(Vec3(0.1f, 0.4f, 0.0f), Vec3(0.9f, 0.6f, 1.0f), 5.0),
          PhongProperties(Vec3(0.0f, 0.0f, 0.0f), Vec3(1.0f, 1.0f, 1.0f), 1.0)};
}

class SurfaceModelTest : public SurfacePluginTest {};

// --- Registration and properties -------------------------------------------

TEST_F(SurfaceModelTest, RegistersEveryModelWithItsInterface) {
  for (const char* name : {"lambertian", "phong", "mirror", "dielectric"})
    ASSERT_NO_FATAL_FAILURE(ExpectRegisteredSurfaceModel(name));
}

TEST_F(SurfaceModelTest, LobesDescribeTheModels) {
  EXPECT_EQ(Make("lambertian")->Lobes(), uint32_t(kScatterReflect | kScatterDiffuse));
  EXPECT_EQ(Make("phong")->Lobes(), uint32_t(kScatterReflect | kScatterDiffuse | kScatterGlossy));
  Properties glossy_only;
  glossy_only.Set("diffuse_reflectance", 0.0);
  EXPECT_EQ(Make("phong", glossy_only)->Lobes(), uint32_t(kScatterReflect | kScatterGlossy));
  EXPECT_EQ(Make("mirror")->Lobes(), uint32_t(kScatterReflect | kScatterDelta));
  EXPECT_EQ(Make("dielectric")->Lobes(),
            uint32_t(kScatterReflect | kScatterRefract | kScatterDelta));
}

TEST_F(SurfaceModelTest, PhongThatCreatesEnergyIsRejected) {
  const std::string message = CreationError(
      "phong", PhongProperties(Vec3(0.7f, 0.5f, 0.5f), Vec3(0.4f, 0.4f, 0.4f), 20.0));
  EXPECT_NE(message.find("diffuse_reflectance"), std::string::npos) << message;
  EXPECT_NE(message.find("specular_reflectance"), std::string::npos) << message;
}

TEST_F(SurfaceModelTest, BadPropertyValuesAreRejectedByName) {
  Properties negative_exponent;
  negative_exponent.Set("exponent", -1.0);
  EXPECT_NE(CreationError("phong", negative_exponent).find("'exponent'"), std::string::npos);

  Properties bright;
  bright.Set("reflectance", Rgb{Vec3(0.5f, 1.5f, 0.5f)});
  EXPECT_NE(CreationError("lambertian", bright).find("'reflectance'"), std::string::npos);
  EXPECT_NE(CreationError("mirror", bright).find("'reflectance'"), std::string::npos);

  Properties negative_index;
  negative_index.Set("int_ior", -1.5);
  EXPECT_NE(CreationError("dielectric", negative_index).find("'int_ior'"), std::string::npos);

  Properties wrong_type;
  wrong_type.Set("reflectance", std::string("red"));
  EXPECT_NE(CreationError("lambertian", wrong_type).find("'reflectance'"), std::string::npos);
}

TEST_F(SurfaceModelTest, UnknownPropertyIsRejected) {
  for (const char* name : {"lambertian", "phong", "mirror", "dielectric"}) {
    Properties props;
    props.Set("reflectanse", 0.5);
    const std::string message = CreationError(name, props);
    EXPECT_NE(message.find("'reflectanse'"), std::string::npos) << name << ": " << message;
  }
}

// --- Energy conservation --------------------------------------------------

TEST_F(SurfaceModelTest, LambertianAlbedoIsItsReflectance) {
  const Vec3 reflectance(0.2f, 0.5f, 0.9f);
  Properties props;
  props.Set("reflectance", Rgb{reflectance});
  const auto model = Make("lambertian", props);
  for (Vec3 wi : IncidentDirections()) {
    ExpectVecNear(AlbedoByQuadrature(*model, wi), reflectance, 0.01f,
                  "quadrature at wi " + Describe(wi));
    ExpectVecNear(MeanWeight(SampleMany(*model, wi, 10000, 1)).mean, reflectance, 0.01f,
                  "sampling at wi " + Describe(wi));
  }
  const Vec3 default_albedo = AlbedoByQuadrature(*Make("lambertian"), Vec3(0, 0, 1));
  ExpectVecNear(default_albedo, Vec3(0.5f, 0.5f, 0.5f), 0.01f, "default reflectance");
}

TEST_F(SurfaceModelTest, PhongConservesEnergy) {
  for (const Properties& props : PhongVariants()) {
    const auto model = Make("phong", props);
    for (Vec3 wi : IncidentDirections()) {
      const Vec3 quadrature = AlbedoByQuadrature(*model, wi);
      const MeanWithError sampled = MeanWeight(SampleMany(*model, wi, 200000, 7));
      for (int c = 0; c < 3; ++c) {
        const std::string where = "wi " + Describe(wi) + " channel " + std::to_string(c);
        EXPECT_LE(quadrature[c], 1.0f + 2e-3f) << where;
        EXPECT_LE(sampled.mean[c], 1.0f + 4 * sampled.standard_error[c]) << where;
        // Both estimate the same integral.
        EXPECT_NEAR(sampled.mean[c], quadrature[c], 5 * sampled.standard_error[c] + 5e-3f) << where;
      }
    }
  }
}

TEST_F(SurfaceModelTest, PhongAtNormalIncidenceReflectsKdPlusKs) {
  // At normal incidence the glossy lobe lies wholly above the surface, so
  // the albedo is exactly kd + ks.
  const auto model = Make("phong", PhongVariants()[1]);
  ExpectVecNear(AlbedoByQuadrature(*model, Vec3(0, 0, 1)), Vec3(1, 1, 1), 5e-3f, "albedo");
}

// --- Reciprocity and two-sidedness ------------------------------------------

TEST_F(SurfaceModelTest, LambertianAndPhongAreReciprocal) {
  for (const char* name : {"lambertian", "phong"}) {
    const auto model = Make(name);
    for (uint64_t k = 0; k < 2000; ++k) {
      const auto u = Uniform3(11, k), v = Uniform3(12, k);
      const Vec3 a = SampleUniformSphere(u[0], u[1]), b = SampleUniformSphere(v[0], v[1]);
      ExpectVecNear(EvaluateOne(*model, a, b), EvaluateOne(*model, b, a), 1e-5f,
                    std::string(name) + " f(a, b) vs f(b, a)");
      EXPECT_EQ(PdfOne(*model, a, b) > 0, a.z * b.z > 0) << name << " reflects only";
    }
  }
}

TEST_F(SurfaceModelTest, LambertianAndPhongAreTwoSided) {
  for (const char* name : {"lambertian", "phong"}) {
    const auto model = Make(name);
    for (uint64_t k = 0; k < 500; ++k) {
      const auto u = Uniform3(21, k), v = Uniform3(22, k);
      const Vec3 a = SampleUniformHemisphere(u[0], u[1]), b = SampleUniformHemisphere(v[0], v[1]);
      const Vec3 a_below(a.x, a.y, -a.z), b_below(b.x, b.y, -b.z);
      ExpectVecNear(EvaluateOne(*model, a_below, b_below), EvaluateOne(*model, a, b), 1e-5f,
                    std::string(name) + " back side");
      EXPECT_NEAR(PdfOne(*model, a_below, b_below), PdfOne(*model, a, b), 1e-4f) << name;
    }
  }
}

TEST_F(SurfaceModelTest, OneSidedLambertianIsBlackFromBehind) {
  Properties props;
  props.Set("two_sided", false);
  const auto one_sided = Make("lambertian", props), two_sided = Make("lambertian");
  for (uint64_t k = 0; k < 500; ++k) {
    const auto u = Uniform3(23, k), v = Uniform3(24, k);
    const Vec3 a = SampleUniformHemisphere(u[0], u[1]), b = SampleUniformHemisphere(v[0], v[1]);
    const Vec3 a_below(a.x, a.y, -a.z), b_below(b.x, b.y, -b.z);
    ExpectVecNear(EvaluateOne(*one_sided, a, b), EvaluateOne(*two_sided, a, b), 0, "front side");
    EXPECT_EQ(PdfOne(*one_sided, a, b), PdfOne(*two_sided, a, b));
    ExpectVecNear(EvaluateOne(*one_sided, a_below, b_below), Vec3(), 0, "back side");
    EXPECT_EQ(PdfOne(*one_sided, a_below, b_below), 0.0f);
    const Scattered s = SampleOne(*one_sided, a_below, Uniform3(25, k));
    EXPECT_EQ(s.pdf, 0.0f);
    EXPECT_EQ(s.flags, uint32_t(kScatterNone));
  }
  const Vec3 reflectance(0.5f, 0.5f, 0.5f);
  ExpectVecNear(MeanWeight(SampleMany(*one_sided, Normalize(Vec3(0.2f, 0.1f, 0.9f)), 10000, 2)).mean, reflectance,
                0.01f, "albedo of the front side");
}

// --- Sample agrees with Pdf and Evaluate ---------------------------------

TEST_F(SurfaceModelTest, SampleAgreesWithPdfAndEvaluate) {
  std::vector<std::pair<std::string, Properties>> models = {{"lambertian", Properties()}};
  for (const Properties& props : PhongVariants()) models.push_back({"phong", props});
  for (const auto& [name, props] : models) {
    const auto model = Make(name, props);
    int produced = 0;
    for (Vec3 wi : IncidentDirections())
      for (uint64_t k = 0; k < 2000; ++k) {
        const Scattered s = SampleOne(*model, wi, Uniform3(31, k));
        if (s.pdf == 0) {
          EXPECT_EQ(s.flags, uint32_t(kScatterNone));
          ExpectVecNear(s.weight, Vec3(), 0, name + " weight without a sample");
          continue;
        }
        ++produced;
        const std::string where = name + " wi " + Describe(wi) + " wo " + Describe(s.wo);
        EXPECT_TRUE(s.flags == (kScatterReflect | kScatterDiffuse) ||
                    s.flags == (kScatterReflect | kScatterGlossy))
            << where;
        EXPECT_EQ(s.flags & ~model->Lobes(), 0u) << where;
        EXPECT_NEAR(Length(s.wo), 1.0f, 1e-4f) << where;
        EXPECT_GT(wi.z * s.wo.z, 0.0f) << where;
        const float pdf = PdfOne(*model, wi, s.wo);
        EXPECT_NEAR(s.pdf, pdf, 1e-4f * std::max(1.0f, pdf)) << where;
        ExpectVecNear(s.weight, EvaluateOne(*model, wi, s.wo) * (std::abs(s.wo.z) / pdf), 1e-4f,
                      where);
      }
    EXPECT_GT(produced, 12 * 2000 / 2) << name;
  }
}

TEST_F(SurfaceModelTest, SampleHonoursAllowedLobes) {
  const Vec3 wi = Normalize(Vec3(0.3f, 0.2f, 0.8f));
  const std::array<float, 3> u = {0.3f, 0.6f, 0.2f};
  for (const char* name : {"lambertian", "phong"}) {
    const auto model = Make(name);
    EXPECT_EQ(SampleOne(*model, wi, u, kScatterReflect | kScatterDiffuse).flags,
              uint32_t(kScatterReflect | kScatterDiffuse))
        << name;
    for (uint32_t allowed : {uint32_t(kScatterRefract), uint32_t(kScatterDelta),
                             uint32_t(kScatterReflect), uint32_t(kScatterReflect | kScatterDelta)}) {
      const Scattered none = SampleOne(*model, wi, u, allowed);
      EXPECT_EQ(none.flags, uint32_t(kScatterNone)) << name;
      EXPECT_EQ(none.pdf, 0.0f) << name;
      ExpectVecNear(none.weight, Vec3(), 0, name);
    }
  }
}

TEST_F(SurfaceModelTest, PhongRestrictedToOneLobeSamplesThatLobe) {
  // Only the diffuse lobe: its weight is kd exactly. Only the glossy lobe:
  // every sample is glossy, and the mean weight is the glossy lobe's
  // albedo, ks at normal incidence.
  Properties props;
  props.Set("diffuse_reflectance", 0.5);
  props.Set("specular_reflectance", 0.3);
  props.Set("exponent", 20.0);
  const auto model = Make("phong", props);
  const Vec3 normal(0, 0, 1);
  double glossy_sum = 0;
  constexpr int kCount = 20000;
  for (int k = 0; k < kCount; ++k) {
    const Scattered d = SampleOne(*model, normal, Uniform3(5, k), kScatterReflect | kScatterDiffuse);
    ASSERT_EQ(d.flags, uint32_t(kScatterReflect | kScatterDiffuse));
    ExpectVecNear(d.weight, Vec3(0.5f, 0.5f, 0.5f), 1e-5f, "diffuse weight");
    const Scattered g = SampleOne(*model, normal, Uniform3(6, k), kScatterReflect | kScatterGlossy);
    ASSERT_TRUE(g.flags == (kScatterReflect | kScatterGlossy) || g.flags == kScatterNone);
    glossy_sum += g.weight.x;
  }
  EXPECT_NEAR(glossy_sum / kCount, 0.3, 0.01);
}

TEST_F(SurfaceModelTest, PhongSamplesFollowItsPdf) {
  constexpr int kCount = 1'000'000;
  for (double exponent : {5.0, 30.0}) {
    const auto model =
        Make("phong", PhongProperties(Vec3(0.3f, 0.3f, 0.3f), Vec3(0.5f, 0.5f, 0.5f), exponent));
    for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.5, 1.0), DirectionAt(-0.8, -2.0)}) {
      std::vector<std::array<float, 3>> uniform(kCount);
      for (int k = 0; k < kCount; ++k) uniform[k] = Uniform3(41, k);
      std::vector<Vec3> directions;
      for (const Scattered& s : SampleBatch(*model, std::vector<Vec3>(kCount, wi), uniform))
        if (s.pdf > 0) directions.push_back(s.wo);
      EXPECT_TRUE(DirectionsFollowPdf(directions, kCount,
                                      [&](Vec3 wo) { return PdfOne(*model, wi, wo); }))
          << "exponent " << exponent << ", wi " << Describe(wi);
    }
  }
}

// --- Mirror -------------------------------------------------------------

TEST_F(SurfaceModelTest, MirrorReflectsExactly) {
  Properties props;
  props.Set("reflectance", Rgb{Vec3(0.9f, 0.8f, 0.7f)});
  const auto model = Make("mirror", props);
  for (uint64_t k = 0; k < 1000; ++k) {
    const auto u = Uniform3(51, k);
    const Vec3 wi = SampleUniformSphere(u[0], u[1]);
    const Scattered s = SampleOne(*model, wi, Uniform3(52, k));
    EXPECT_EQ(s.wo.x, -wi.x);
    EXPECT_EQ(s.wo.y, -wi.y);
    EXPECT_EQ(s.wo.z, wi.z);
    ExpectVecNear(s.weight, Vec3(0.9f, 0.8f, 0.7f), 0, "weight");
    EXPECT_EQ(s.pdf, 1.0f);
    EXPECT_EQ(s.flags, uint32_t(kScatterReflect | kScatterDelta));
    // A delta lobe has no finite value or density.
    ExpectVecNear(EvaluateOne(*model, wi, s.wo), Vec3(), 0, "Evaluate");
    EXPECT_EQ(PdfOne(*model, wi, s.wo), 0.0f);
  }
  const Vec3 wi = Normalize(Vec3(0.1f, 0.2f, 0.9f));
  EXPECT_EQ(SampleOne(*model, wi, {0.5f, 0.5f, 0.5f}, kScatterReflect | kScatterDelta).flags,
            uint32_t(kScatterReflect | kScatterDelta));
  EXPECT_EQ(SampleOne(*model, wi, {0.5f, 0.5f, 0.5f}, kScatterRefract | kScatterDelta).flags,
            uint32_t(kScatterNone));
  ExpectVecNear(SampleOne(*Make("mirror"), wi, {0.5f, 0.5f, 0.5f}).weight, Vec3(1, 1, 1), 0,
                "default reflectance");
}

// --- Dielectric -------------------------------------------------------------

class DielectricTest : public SurfaceModelTest {
 protected:
  static constexpr float kEta = float(1.5046 / 1.000277);  // the defaults
  static constexpr int kStrata = 10000;

  // cos θi from outside (> 0) and inside (< 0), the latter partly beyond
  // the critical angle.
  static std::vector<Vec3> Directions() {
    std::vector<Vec3> out;
    for (float cos_theta : {1.0f, 0.8f, 0.5f, 0.2f, 0.05f, -1.0f, -0.9f, -0.75f, -0.6f, -0.2f})
      out.push_back(DirectionAt(cos_theta, 0.3 + cos_theta));
    return out;
  }
  // η of wo's side over wi's side for a refraction.
  static float RefractedEta(Vec3 wi) { return wi.z > 0 ? kEta : 1.0f / kEta; }

  // Samples at uniform[0] = (k + ½)/kStrata: the lobe choice, stratified.
  std::vector<Scattered> StratifiedSamples(const SurfaceModel& model, Vec3 wi,
                                           uint32_t allowed = 0) const {
    std::vector<std::array<float, 3>> uniform(kStrata);
    for (int k = 0; k < kStrata; ++k) uniform[k] = {(k + 0.5f) / kStrata, 0.5f, 0.5f};
    return SampleBatch(model, std::vector<Vec3>(kStrata, wi), uniform, allowed);
  }
};

TEST_F(DielectricTest, LobeProbabilitiesAreFresnel) {
  const auto model = Make("dielectric");
  for (Vec3 wi : Directions()) {
    const float fresnel = FresnelDielectric(wi.z, kEta);
    int reflected = 0;
    float reflect_pdf = -1, refract_pdf = 0;
    for (const Scattered& s : StratifiedSamples(*model, wi)) {
      ASSERT_NE(s.flags, uint32_t(kScatterNone)) << "wi " << Describe(wi);
      if (s.flags & kScatterReflect) {
        ++reflected;
        reflect_pdf = s.pdf;
      } else {
        refract_pdf = s.pdf;
      }
    }
    EXPECT_NEAR(reflected / double(kStrata), fresnel, 1.0 / kStrata) << "wi " << Describe(wi);
    EXPECT_NEAR(reflect_pdf, fresnel, 1e-6f) << "wi " << Describe(wi);
    if (fresnel < 1) {
      EXPECT_NEAR(refract_pdf, 1.0f - fresnel, 1e-6f) << "wi " << Describe(wi);
      EXPECT_NEAR(reflect_pdf + refract_pdf, 1.0f, 1e-6f);
    }
  }
  // Beyond the critical angle from inside, only reflection remains.
  EXPECT_EQ(FresnelDielectric(-0.2f, kEta), 1.0f);
}

TEST_F(DielectricTest, DirectionsFollowReflectionAndSnell) {
  const auto model = Make("dielectric");
  for (Vec3 wi : Directions())
    for (const Scattered& s : StratifiedSamples(*model, wi)) {
      if (s.flags == (kScatterReflect | kScatterDelta)) {
        EXPECT_EQ(s.wo.x, -wi.x);
        EXPECT_EQ(s.wo.y, -wi.y);
        EXPECT_EQ(s.wo.z, wi.z);
        continue;
      }
      ASSERT_EQ(s.flags, uint32_t(kScatterRefract | kScatterDelta));
      const float eta_i = wi.z > 0 ? 1.0f : kEta, eta_t = wi.z > 0 ? kEta : 1.0f;
      EXPECT_LT(wi.z * s.wo.z, 0.0f);
      EXPECT_NEAR(Length(s.wo), 1.0f, 1e-5f);
      EXPECT_NEAR(eta_i * SinFromCos(wi.z), eta_t * SinFromCos(s.wo.z), 1e-5f);
    }
}

TEST_F(DielectricTest, LosslessInTheWhiteFurnace) {
  // Every sample's weight is (Fresnel factor)/(lobe probability): 1 for
  // reflection, 1/η² for refraction. Undoing the radiance scaling, the
  // interface neither creates nor destroys energy.
  const auto model = Make("dielectric");
  for (Vec3 wi : Directions()) {
    const float eta2 = RefractedEta(wi) * RefractedEta(wi);
    const float fresnel = FresnelDielectric(wi.z, kEta);
    double energy = 0, radiance = 0;
    for (const Scattered& s : StratifiedSamples(*model, wi)) {
      const bool refracted = s.flags & kScatterRefract;
      EXPECT_NEAR(s.weight.x, refracted ? 1.0f / eta2 : 1.0f, 1e-5f);
      EXPECT_EQ(s.weight.x, s.weight.y);
      EXPECT_EQ(s.weight.x, s.weight.z);
      energy += s.weight.x * (refracted ? eta2 : 1.0f);
      radiance += s.weight.x;
    }
    EXPECT_NEAR(energy / kStrata, 1.0, 1e-5) << "wi " << Describe(wi);
    EXPECT_NEAR(radiance / kStrata, fresnel + (1 - fresnel) / eta2, 2.0 / kStrata)
        << "wi " << Describe(wi);
  }
}

TEST_F(DielectricTest, AllowedLobeCarriesItsFresnelFactor) {
  const auto model = Make("dielectric");
  constexpr uint32_t kReflect = kScatterReflect | kScatterDelta;
  constexpr uint32_t kRefract = kScatterRefract | kScatterDelta;
  for (Vec3 wi : Directions()) {
    const float fresnel = FresnelDielectric(wi.z, kEta);
    const std::array<float, 3> u = {0.999f, 0.5f, 0.5f};
    const Scattered reflected = SampleOne(*model, wi, u, kReflect);
    EXPECT_EQ(reflected.flags, kReflect);
    EXPECT_EQ(reflected.pdf, 1.0f);
    EXPECT_NEAR(reflected.weight.x, fresnel, 1e-6f);
    const Scattered refracted = SampleOne(*model, wi, {0.001f, 0.5f, 0.5f}, kRefract);
    if (fresnel < 1) {
      EXPECT_EQ(refracted.flags, kRefract);
      EXPECT_EQ(refracted.pdf, 1.0f);
      const float eta = RefractedEta(wi);
      EXPECT_NEAR(refracted.weight.x, (1 - fresnel) / (eta * eta), 1e-6f);
    } else {
      EXPECT_EQ(refracted.flags, uint32_t(kScatterNone));
      EXPECT_EQ(refracted.weight.x, 0.0f);
    }
    // Non-delta lobes only: the dielectric has none.
    EXPECT_EQ(SampleOne(*model, wi, u, kScatterReflect | kScatterRefract).flags,
              uint32_t(kScatterNone));
  }
}

TEST_F(DielectricTest, ImportanceRefractsWithoutRadianceScaling) {
  // Paths from the lights carry importance: the refracted weight is the
  // Fresnel transmittance alone, so each sample's weight is 1.
  const auto model = Make("dielectric");
  for (Vec3 wi : Directions())
    for (float u0 : {0.01f, 0.5f, 0.99f}) {
      const Scattered s = SampleOne(*model, wi, {u0, 0.5f, 0.5f}, 0, TransportMode::kImportance);
      if (s.flags == kScatterNone) continue;
      EXPECT_NEAR(s.weight.x, 1.0f, 1e-5f) << "wi " << Describe(wi);
    }
}

TEST_F(DielectricTest, DeltaLobesHaveNoValueOrDensity) {
  const auto model = Make("dielectric");
  for (Vec3 wi : Directions()) {
    const Scattered s = SampleOne(*model, wi, {0.5f, 0.5f, 0.5f});
    ExpectVecNear(EvaluateOne(*model, wi, s.wo), Vec3(), 0, "Evaluate");
    EXPECT_EQ(PdfOne(*model, wi, s.wo), 0.0f);
  }
}

TEST_F(DielectricTest, MatchedIndicesPassStraightThrough) {
  Properties props;
  props.Set("int_ior", 1.33);
  props.Set("ext_ior", 1.33);
  const auto model = Make("dielectric", props);
  for (Vec3 wi : Directions()) {
    const Scattered s = SampleOne(*model, wi, {0.5f, 0.5f, 0.5f});
    EXPECT_EQ(s.flags, uint32_t(kScatterRefract | kScatterDelta));
    ExpectVecNear(s.wo, -wi, 1e-6f, "direction");
    ExpectVecNear(s.weight, Vec3(1, 1, 1), 1e-6f, "weight");
  }
}

}  // namespace
}  // namespace yarf
