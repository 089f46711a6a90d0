// Tests of roughdiffuse (roughdiffuse.cc) against Oren and Nayar's model
// as their paper writes it, in polar angles and azimuths (the plugin works
// from the directions' components), and of what any reflector must do.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "surface_test_support.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

using namespace surface_testing;  // NOLINT: the shared helpers, in every test

class RoughDiffuseTest : public SurfacePluginTest {};

// Oren and Nayar (1994), eqs. 30 and 32 (full) or the qualitative model
// (fast), in their angles: θ, φ of both directions, α the larger θ, β the
// smaller, σ² = alpha²/2.
Vec3 OrenNayar(Vec3 reflectance, double alpha, bool fast, Vec3 wi, Vec3 wo) {
  const double sigma2 = alpha * alpha / 2;
  const double theta_i = std::acos(double(wi.z)), theta_o = std::acos(double(wo.z));
  const double cos_dphi = std::cos(std::atan2(double(wi.y), double(wi.x)) - std::atan2(double(wo.y), double(wo.x)));
  const double a = std::max(theta_i, theta_o), b = std::min(theta_i, theta_o);
  const double c1 = 1 - 0.5 * sigma2 / (sigma2 + 0.33);
  const double groove = sigma2 / (sigma2 + 0.09);
  if (fast) {
    const double value = c1 + 0.45 * groove * std::max(cos_dphi, 0.0) * std::sin(a) * std::tan(b);
    return reflectance * float(value / kPiDouble);
  }
  const double c2 =
      0.45 * groove * (cos_dphi >= 0 ? std::sin(a) : std::sin(a) - std::pow(2 * b / kPiDouble, 3));
  const double c3 = 0.125 * groove * std::pow(4 * a * b / (kPiDouble * kPiDouble), 2);
  const double single = c1 + cos_dphi * c2 * std::tan(b) + (1 - std::abs(cos_dphi)) * c3 * std::tan((a + b) / 2);
  const double twice = 0.17 * sigma2 / (sigma2 + 0.13) * (1 - cos_dphi * std::pow(2 * b / kPiDouble, 2));
  return (reflectance * float(single) + reflectance * reflectance * float(twice)) * float(1 / kPiDouble);
}

Properties RoughProperties(Vec3 reflectance, double alpha, bool fast) {
  Properties props;
  props.Set("reflectance", Rgb{reflectance});
  props.Set("alpha", alpha);
  props.Set("use_fast_approx", fast);
  return props;
}

TEST_F(RoughDiffuseTest, EvaluatesOrenAndNayarsModel) {
  const Vec3 reflectance(0.9f, 0.5f, 0.2f);
  for (const double alpha : {0.1, 0.5, 1.0, 2.0})
    for (const bool fast : {false, true}) {
      const auto model = Make("roughdiffuse", RoughProperties(reflectance, alpha, fast));
      for (uint64_t k = 0; k < 500; ++k) {
        const auto u = Uniform3(41, k), v = Uniform3(42, k);
        const Vec3 wi = SampleUniformSphere(u[0], u[1]), wo = SampleUniformSphere(v[0], v[1]);
        // Away from the horizon, where tan β grows without bound.
        if (std::abs(wi.z) < 0.05f || std::abs(wo.z) < 0.05f) continue;
        const std::string where = "alpha " + std::to_string(alpha) + (fast ? " fast" : " full") + " wi " +
                                  Describe(wi) + " wo " + Describe(wo);
        // Both sides alike: a pair below is the pair above mirrored.
        const float side = wi.z > 0 ? 1.0f : -1.0f;
        const Vec3 expected = wi.z * wo.z > 0 ? OrenNayar(reflectance, alpha, fast, wi * side, wo * side) : Vec3();
        ExpectVecNear(EvaluateOne(*model, wi, wo), expected, 1e-3f, where);
      }
    }
}

TEST_F(RoughDiffuseTest, SmoothGroovesAreLambertian) {
  const Vec3 reflectance(0.3f, 0.6f, 0.9f);
  Properties lambertian_props;
  lambertian_props.Set("reflectance", Rgb{reflectance});
  const auto lambertian = Make("lambertian", lambertian_props);
  for (const bool fast : {false, true}) {
    const auto model = Make("roughdiffuse", RoughProperties(reflectance, 0, fast));
    for (uint64_t k = 0; k < 200; ++k) {
      const Vec3 wi = SampleUniformSphere(Uniform3(43, k)[0], Uniform3(43, k)[1]);
      const Vec3 wo = SampleUniformSphere(Uniform3(44, k)[0], Uniform3(44, k)[1]);
      ExpectVecNear(EvaluateOne(*model, wi, wo), EvaluateOne(*lambertian, wi, wo), 1e-6f, "alpha 0");
    }
  }
}

TEST_F(RoughDiffuseTest, RoughGroovesScatterBackTowardTheLight) {
  // Light at 70° from the normal: seen from the light's side a rough
  // surface is brighter than a Lambertian one, seen from the far side
  // darker (Oren and Nayar's figures; the moon's flat full face).
  const auto model = Make("roughdiffuse", RoughProperties(Vec3(0.5f, 0.5f, 0.5f), 1.0, false));
  const Vec3 light = DirectionAt(std::cos(70 * kPiDouble / 180), 0);
  const float lambertian = 0.5f / float(kPiDouble);
  EXPECT_GT(EvaluateOne(*model, light, DirectionAt(std::cos(60 * kPiDouble / 180), 0)).x, 1.3f * lambertian);
  EXPECT_LT(EvaluateOne(*model, light, DirectionAt(std::cos(60 * kPiDouble / 180), kPiDouble)).x, lambertian);
}

TEST_F(RoughDiffuseTest, ReciprocalAndSampledAsItsPdfSays) {
  for (const bool fast : {false, true}) {
    const auto model = Make("roughdiffuse", RoughProperties(Vec3(0.8f, 0.4f, 0.1f), 0.8, fast));
    for (uint64_t k = 0; k < 2000; ++k) {
      const auto u = Uniform3(45, k), v = Uniform3(46, k);
      const Vec3 a = SampleUniformSphere(u[0], u[1]), b = SampleUniformSphere(v[0], v[1]);
      ExpectVecNear(EvaluateOne(*model, a, b), EvaluateOne(*model, b, a), 1e-5f, "f(a, b) vs f(b, a)");
      EXPECT_EQ(PdfOne(*model, a, b) > 0, a.z * b.z > 0) << "reflects only, on both sides";
      const Vec3 wi = a.z == 0 ? Vec3(0, 0, 1) : a;
      const Scattered s = SampleOne(*model, wi, Uniform3(47, k));
      ASSERT_GT(s.pdf, 0.0f) << Describe(wi);
      EXPECT_GT(wi.z * s.wo.z, 0.0f);
      EXPECT_EQ(s.flags, uint32_t(kScatterReflect | kScatterDiffuse));
      EXPECT_NEAR(s.pdf, PdfOne(*model, wi, s.wo), 1e-4f * std::max(1.0f, s.pdf));
      ExpectVecNear(s.weight, EvaluateOne(*model, wi, s.wo) * (std::abs(s.wo.z) / s.pdf), 1e-4f, "weight");
    }
    // The sampled directions follow the cosine-weighted pdf.
    const Vec3 wi = Normalize(Vec3(0.5f, -0.2f, 0.6f));
    std::vector<Vec3> directions;
    for (const Scattered& s : SampleMany(*model, wi, 100000, 48)) directions.push_back(s.wo);
    EXPECT_TRUE(DirectionsFollowPdf(*model, wi, directions, 100000));
  }
}

TEST_F(RoughDiffuseTest, OneSidedIsBlackFromBehind) {
  Properties props = RoughProperties(Vec3(0.5f, 0.5f, 0.5f), 0.5, false);
  props.Set("two_sided", false);
  const auto model = Make("roughdiffuse", props);
  const Vec3 a = Normalize(Vec3(0.2f, 0.3f, -0.9f)), b = Normalize(Vec3(-0.4f, 0.1f, -0.5f));
  ExpectVecNear(EvaluateOne(*model, a, b), Vec3(), 0, "back side");
  EXPECT_EQ(PdfOne(*model, a, b), 0.0f);
  EXPECT_EQ(SampleOne(*model, a, {0.3f, 0.4f, 0.5f}).pdf, 0.0f);
  EXPECT_GT(EvaluateOne(*model, -a, -b).x, 0.0f);
}

TEST_F(RoughDiffuseTest, HugeSlopesGiveFiniteValues) {
  const auto model = Make("roughdiffuse", RoughProperties(Vec3(1, 1, 1), 1e30, false));
  const Vec3 f = EvaluateOne(*model, Normalize(Vec3(0.3f, 0.1f, 0.9f)), Normalize(Vec3(-0.5f, 0.2f, 0.4f)));
  EXPECT_TRUE(std::isfinite(f.x) && f.x > 0) << Describe(f);
  ExpectVecNear(f, OrenNayar(Vec3(1, 1, 1), 100, false, Normalize(Vec3(0.3f, 0.1f, 0.9f)),
                             Normalize(Vec3(-0.5f, 0.2f, 0.4f))),
                1e-3f, "as at alpha 100");
}

TEST_F(RoughDiffuseTest, BadSlopesAreRefusedByName) {
  for (const double alpha : {-0.1, std::nan(""), std::numeric_limits<double>::infinity()}) {
    Properties props;
    props.Set("alpha", alpha);
    EXPECT_NE(CreationError("roughdiffuse", props).find("'alpha'"), std::string::npos) << alpha;
  }
}

}  // namespace
}  // namespace yarf
