// Tests of the two Disney surface plugins, principled and principledthin
// (the thin sheet), loaded through the registry as yarfd loads them:
// Pearson's χ² test of Sample's directions against Pdf, Sample agreeing
// with Pdf and Evaluate, Pdf integrating to the rate at which Sample
// succeeds, reciprocity, energy (white furnace) over parameter sets that
// each turn one lobe fully on, the lobes `allowed` leaves, textured
// parameters, and property checking. The statistical tests run over the
// materials of both models.
//
// The fixture, batch calls and χ² binning are surface_test_support.h's;
// the sphere quadrature is uniform in θ, as microfacet_test.cc's, to
// resolve lobes near the pole.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "surface_test_support.h"
#include "yarf/surface.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

using namespace surface_testing;  // NOLINT: the shared helpers, in every test

constexpr TransportMode kRadiance = TransportMode::kRadiance;
constexpr TransportMode kImportance = TransportMode::kImportance;

// A material of each kind, named for the messages: each lobe of each
// model turned fully on at least once. (The thin sheet's transmission is
// narrower than its roughness says: rough enough that the sphere
// quadrature resolves it at grazing incidence.)
struct Variant {
  std::string model, name;
  Properties props;
  // Whether light arriving from below (wi.z < 0) scatters: the glass,
  // and both sides of the thin sheet.
  bool below = false;
};

std::vector<Variant> Variants() {
  const Rgb white{Vec3(1.0f, 1.0f, 1.0f)};
  return {
      {"principled", "default", Properties()},
      {"principled", "coated", Props({{"metallic", 0.3}, {"roughness", 0.4}, {"clearcoat", 0.5}})},
      {"principled", "metal",
       Props({{"metallic", 1.0}, {"roughness", 0.4}, {"base_color", Rgb{Vec3(1.0f, 0.8f, 0.5f)}}})},
      {"principled", "glass", Props({{"spec_trans", 1.0}, {"roughness", 0.4}, {"base_color", white}}), true},
      {"principled", "glassy", Props({{"spec_trans", 0.8}, {"roughness", 0.5}, {"eta", 1.33}, {"spec_tint", 0.5}}),
       true},
      {"principled", "clearcoat", Props({{"clearcoat", 1.0}, {"clearcoat_gloss", 0.3}, {"roughness", 0.7}})},
      {"principled", "sheen", Props({{"sheen", 1.0}, {"sheen_tint", 0.5}, {"roughness", 0.9}, {"flatness", 0.5}})},
      {"principled", "anisotropic",
       Props({{"anisotropic", 0.8}, {"roughness", 0.6}, {"metallic", 0.5}, {"specular", 0.8}})},
      {"principledthin", "thin default", Properties(), true},
      {"principledthin", "thin sheet", Props({{"spec_trans", 1.0}, {"roughness", 0.6}, {"base_color", white}}), true},
      {"principledthin", "thin dense sheet",
       Props({{"spec_trans", 0.7}, {"roughness", 0.5}, {"eta", 2.5}, {"spec_tint", 0.6}}), true},
      {"principledthin", "thin translucent",
       Props({{"diff_trans", 2.0}, {"roughness", 0.6}, {"base_color", Rgb{Vec3(0.3f, 0.7f, 0.2f)}}}), true},
      {"principledthin", "thin mixed",
       Props({{"spec_trans", 0.5}, {"diff_trans", 0.8}, {"anisotropic", 0.7}, {"roughness", 0.5}, {"eta", 1.33},
              {"sheen", 0.5}, {"flatness", 0.4}}),
       true},
      {"principledthin", "thin sheen",
       Props({{"sheen", 1.0}, {"sheen_tint", 0.5}, {"roughness", 0.9}, {"flatness", 0.5}, {"diff_trans", 0.5}}),
       true},
      {"principledthin", "thin rates",
       Props({{"spec_trans", 0.4}, {"diff_trans", 1.0}, {"roughness", 0.6}, {"specular_reflectance_sampling_rate", 0.2},
              {"specular_transmittance_sampling_rate", 3.0}, {"diffuse_reflectance_sampling_rate", 0.5},
              {"diffuse_transmittance_sampling_rate", 2.0}}),
       true},
  };
}

// Incident directions from normal to near-grazing incidence; with
// `below`, their mirror images under the surface too (the glass).
std::vector<Vec3> Incident(bool below) {
  std::vector<Vec3> out;
  for (float cos_theta : {1.0f, 0.8f, 0.5f, 0.2f, 0.05f}) {
    out.push_back(DirectionAt(cos_theta, 0.7 + 2.0 * cos_theta));
    if (below) out.push_back(DirectionAt(-cos_theta, -0.4 + cos_theta));
  }
  return out;
}

// A texture of two cells: `left` where u < 1/2, `right` elsewhere.
class TwoCells final : public Texture {
 public:
  TwoCells(uint32_t channels, Vec3 left, Vec3 right) : channels_(channels), left_(left), right_(right) {}

  uint32_t Channels() const override { return channels_; }
  void Evaluate(const SurfacePoints& at, std::span<float> value) const override {
    for (size_t k = 0; k < at.Count(); ++k)
      for (uint32_t c = 0; c < channels_; ++c) value[channels_ * k + c] = (at.uv[2 * k] < 0.5f ? left_ : right_)[c];
  }
  std::vector<float> Mean() const override { return std::vector<float>(channels_, 0.5f * (left_.x + right_.x)); }

 private:
  uint32_t channels_;
  Vec3 left_, right_;
};

// 'name', as error messages quote a property.
std::string Quoted(const char* name) {
  std::string out(1, '\'');
  out.append(name).push_back('\'');
  return out;
}

class PrincipledTest : public SurfacePluginTest {
 protected:
  // Each parameter in `names` of `model_name`, given as a texture of two
  // cells, acts at each point (in Evaluate, Pdf and Sample) as the
  // constant of the cell's value there; `others` sets the rest.
  void ExpectTexturesActAsConstants(const std::string& model_name, const Properties& others,
                                    std::initializer_list<const char*> names) const {
    const Vec3 left(0.2f, 0.3f, 0.1f), right(0.7f, 0.6f, 0.9f);
    for (const char* name : names) {
      const bool colour = std::string(name) == "base_color";
      Properties textured = others, at_left = others, at_right = others;
      textured.Set(name, std::shared_ptr<const Texture>(std::make_shared<TwoCells>(colour ? 3 : 1, left, right)));
      at_left.Set(name, colour ? Properties::Value(Rgb{left}) : Properties::Value(double(left.x)));
      at_right.Set(name, colour ? Properties::Value(Rgb{right}) : Properties::Value(double(right.x)));
      const auto model = Make(model_name, textured);
      const auto left_model = Make(model_name, at_left), right_model = Make(model_name, at_right);
      // One batch: rows alternate between the cells.
      constexpr size_t kRows = 400;
      std::vector<float> wi(3 * kRows), wo(3 * kRows), uv(2 * kRows), uniform(3 * kRows);
      for (size_t k = 0; k < kRows; ++k) {
        const auto u = Uniform3(210, k), w = Uniform3(211, k), x = Uniform3(212, k);
        SampleUniformSphere(u[0], u[1]).Store(&wi[3 * k]);
        SampleUniformSphere(w[0], w[1]).Store(&wo[3 * k]);
        uv[2 * k] = k % 2 ? 0.25f : 0.75f;
        std::copy(x.begin(), x.end(), &uniform[3 * k]);
      }
      const SurfacePoints points{.uv = uv};
      std::vector<float> value(3 * kRows), pdf(kRows), sampled(3 * kRows), weight(3 * kRows), sampled_pdf(kRows);
      std::vector<uint32_t> flags(kRows);
      model->Evaluate(kRadiance, wi, wo, points, value);
      model->Pdf(wi, wo, points, pdf);
      model->Sample(kRadiance, wi, points, uniform, 0, sampled, weight, sampled_pdf, flags);
      for (size_t k = 0; k < kRows; ++k) {
        const SurfaceModel& constant = k % 2 ? *left_model : *right_model;
        const Vec3 in = Vec3::Load(&wi[3 * k]), out = Vec3::Load(&wo[3 * k]);
        const std::string where = std::string(name) + " row " + std::to_string(k);
        ExpectVecNear(Vec3::Load(&value[3 * k]), EvaluateOne(constant, in, out), 1e-5f, where + " value");
        EXPECT_NEAR(pdf[k], PdfOne(constant, in, out), 1e-5f * std::max(1.0f, pdf[k])) << where;
        const Scattered s = SampleOne(constant, in, {uniform[3 * k], uniform[3 * k + 1], uniform[3 * k + 2]});
        ExpectVecNear(Vec3::Load(&sampled[3 * k]), s.wo, 1e-5f, where + " wo");
        ExpectVecNear(Vec3::Load(&weight[3 * k]), s.weight, 1e-4f, where + " weight");
        EXPECT_EQ(flags[k], s.flags) << where;
      }
    }
  }
};

// --- Registration and properties -------------------------------------------

TEST_F(PrincipledTest, IsRegisteredWithItsLobes) {
  ASSERT_NO_FATAL_FAILURE(ExpectRegisteredSurfaceModel("principled"));
  EXPECT_EQ(Make("principled")->Lobes(), uint32_t(kScatterReflect | kScatterDiffuse | kScatterGlossy));
  EXPECT_EQ(Make("principled", Props({{"spec_trans", 0.5}}))->Lobes(),
            uint32_t(kScatterReflect | kScatterRefract | kScatterDiffuse | kScatterGlossy));
}

TEST_F(PrincipledTest, BadPropertiesAreRejectedByName) {
  const auto expect_error = [&](const Properties& props, std::initializer_list<const char*> mentions) {
    const std::string message = CreationError("principled", props);
    EXPECT_FALSE(message.empty()) << mentions.begin()[0];
    for (const char* text : mentions) EXPECT_NE(message.find(text), std::string::npos) << message;
  };
  for (const char* name : {"roughness", "anisotropic", "metallic", "spec_trans", "spec_tint", "sheen",
                           "sheen_tint", "flatness", "clearcoat", "clearcoat_gloss", "specular"}) {
    const std::string quoted = Quoted(name);
    expect_error(Props({{name, -0.1}}), {quoted.c_str()});
    expect_error(Props({{name, 1.5}}), {quoted.c_str()});
  }
  expect_error(Props({{"base_color", Rgb{Vec3(0.5f, 1.2f, 0.5f)}}}), {"'base_color'"});
  expect_error(Props({{"eta", 1.5}, {"specular", 0.5}}), {"'eta'", "'specular'"});
  expect_error(Props({{"eta", 0.0}}), {"'eta'"});
  expect_error(Props({{"eta", -1.3}}), {"'eta'"});
  for (const char* name : {"diffuse_reflectance_sampling_rate", "main_specular_sampling_rate",
                           "clearcoat_sampling_rate"})
    expect_error(Props({{name, -1.0}}), {name});
  expect_error(Props({{"metalic", 0.5}}), {"'metalic'"});
}

TEST_F(PrincipledTest, ThinSheetIsRegisteredWithItsLobes) {
  ASSERT_NO_FATAL_FAILURE(ExpectRegisteredSurfaceModel("principledthin"));
  EXPECT_EQ(Make("principledthin")->Lobes(), uint32_t(kScatterReflect | kScatterDiffuse));
  EXPECT_EQ(Make("principledthin", Props({{"spec_trans", 0.5}}))->Lobes(),
            uint32_t(kScatterReflect | kScatterRefract | kScatterDiffuse | kScatterGlossy));
  EXPECT_EQ(Make("principledthin", Props({{"diff_trans", 0.5}}))->Lobes(),
            uint32_t(kScatterReflect | kScatterRefract | kScatterDiffuse));
}

TEST_F(PrincipledTest, BadThinPropertiesAreRejectedByName) {
  const auto expect_error = [&](const Properties& props, const std::string& mention) {
    const std::string message = CreationError("principledthin", props);
    EXPECT_NE(message.find(mention), std::string::npos) << mention << ": " << message;
  };
  for (const char* name :
       {"roughness", "anisotropic", "spec_trans", "spec_tint", "sheen", "sheen_tint", "flatness", "diff_trans"}) {
    const std::string quoted = Quoted(name);
    expect_error(Props({{name, -0.1}}), quoted);
    expect_error(Props({{name, 2.5}}), quoted);
  }
  // diff_trans reaches 2 (all of the diffuse lobe transmitted); the others 1.
  EXPECT_EQ(CreationError("principledthin", Props({{"diff_trans", 2.0}})), "");
  expect_error(Props({{"spec_trans", 1.5}}), "[0, 1]");
  expect_error(Props({{"base_color", Rgb{Vec3(0.5f, 1.2f, 0.5f)}}}), "'base_color'");
  expect_error(Props({{"eta", 0.0}}), "'eta'");
  expect_error(Props({{"eta", -1.3}}), "'eta'");
  for (const char* name : {"specular_reflectance_sampling_rate", "specular_transmittance_sampling_rate",
                           "diffuse_reflectance_sampling_rate", "diffuse_transmittance_sampling_rate"})
    expect_error(Props({{name, -1.0}}), name);
  // principled's parameters that the sheet does not have.
  expect_error(Props({{"metallic", 0.5}}), "'metallic'");
  expect_error(Props({{"specular", 0.5}}), "'specular'");
}

// --- Sampling ------------------------------------------------------------------

TEST_F(PrincipledTest, SamplesFollowPdf) {
  for (const Variant& v : Variants()) {
    const auto model = Make(v.model, v.props);
    std::vector<Vec3> incident = {Vec3(0, 0, 1), DirectionAt(0.5, 1.0), DirectionAt(0.15, -2.0)};
    if (v.below) incident.push_back(DirectionAt(-0.6, 0.4));
    for (Vec3 wi : incident) {
      constexpr int kCount = 200000;
      std::vector<Vec3> directions;
      for (const Scattered& s : SampleMany(*model, wi, kCount, 301))
        if (s.pdf > 0) directions.push_back(s.wo);
      EXPECT_TRUE(DirectionsFollowPdf(*model, wi, directions, kCount)) << v.name << ", wi " << Describe(wi);
    }
  }
}

TEST_F(PrincipledTest, SampleAgreesWithPdfAndEvaluate) {
  for (const Variant& v : Variants()) {
    const auto model = Make(v.model, v.props);
    for (TransportMode mode : {kRadiance, kImportance})
      for (Vec3 wi : Incident(v.below)) {
        int produced = 0;
        for (const Scattered& s : SampleMany(*model, wi, 2000, 202, 0, mode)) {
          const std::string where = v.name + " wi " + Describe(wi) + " wo " + Describe(s.wo);
          if (!(s.pdf > 0)) {
            EXPECT_EQ(s.flags, uint32_t(kScatterNone)) << where;
            ExpectVecNear(s.weight, Vec3(), 0, where + " weight without a sample");
            continue;
          }
          ++produced;
          EXPECT_EQ(s.flags & ~model->Lobes(), 0u) << where;
          EXPECT_NEAR(Length(s.wo), 1.0f, 1e-4f) << where;
          if (s.flags & kScatterReflect) {
            EXPECT_GT(wi.z * s.wo.z, 0.0f) << where;
          } else {
            EXPECT_LT(wi.z * s.wo.z, 0.0f) << where;
          }
          const float pdf = PdfOne(*model, wi, s.wo);
          EXPECT_NEAR(s.pdf, pdf, 1e-4f * std::max(1.0f, pdf)) << where;
          ExpectVecNear(s.weight, EvaluateOne(*model, wi, s.wo, mode) * (std::abs(s.wo.z) / pdf), 1e-3f, where);
        }
        // Most draws succeed, except at grazing incidence (masking).
        if (std::abs(wi.z) > 0.1f) {
          EXPECT_GT(produced, 2000 * 3 / 4) << v.name << ", wi " << Describe(wi);
        }
      }
  }
}

TEST_F(PrincipledTest, PdfIntegratesToTheRateOfSamples) {
  for (const Variant& v : Variants()) {
    const auto model = Make(v.model, v.props);
    std::vector<Vec3> incident = {Vec3(0, 0, 1), DirectionAt(0.5, 1.0), DirectionAt(0.15, -2.0)};
    if (v.below) incident.push_back(DirectionAt(-0.6, 0.4));
    for (Vec3 wi : incident) {
      const double integral = IntegrateOverSphere(*model, wi, kRadiance).pdf;
      const double rate = MeanWeight(SampleMany(*model, wi, 100000, 203)).success;
      EXPECT_LE(integral, 1.0 + 2e-3) << v.name << ", wi " << Describe(wi);
      EXPECT_NEAR(integral, rate, 6e-3) << v.name << ", wi " << Describe(wi);
    }
  }
}

TEST_F(PrincipledTest, SampleDrawsOnlyTheAllowedLobes) {
  const auto model = Make("principled", Props({{"spec_trans", 0.5}, {"clearcoat", 1.0}}));
  for (uint32_t allowed : {uint32_t(kScatterReflect | kScatterDiffuse), uint32_t(kScatterReflect | kScatterGlossy),
                           uint32_t(kScatterRefract | kScatterGlossy)})
    for (Vec3 wi : {DirectionAt(0.7, 0.3), DirectionAt(-0.7, 0.3)}) {
      int produced = 0;
      for (const Scattered& s : SampleMany(*model, wi, 2000, 204, allowed)) {
        if (!(s.pdf > 0)) continue;
        ++produced;
        EXPECT_TRUE(LobeAllowed(s.flags, allowed)) << s.flags << " under " << allowed;
        EXPECT_TRUE(std::isfinite(s.weight.x) && s.weight.x >= 0) << Describe(s.weight);
      }
      // From inside only the glass scatters: no diffuse lobe there.
      const bool possible = wi.z > 0 || allowed != uint32_t(kScatterReflect | kScatterDiffuse);
      EXPECT_EQ(produced > 0, possible) << allowed << ", wi " << Describe(wi);
    }
}

TEST_F(PrincipledTest, ThinSheetDrawsOnlyTheAllowedLobes) {
  const auto model = Make("principledthin", Props({{"spec_trans", 0.5}, {"diff_trans", 1.0}, {"sheen", 0.5}}));
  for (uint32_t allowed : {uint32_t(kScatterReflect | kScatterDiffuse), uint32_t(kScatterRefract | kScatterDiffuse),
                           uint32_t(kScatterReflect | kScatterGlossy), uint32_t(kScatterRefract | kScatterGlossy)})
    for (Vec3 wi : {DirectionAt(0.7, 0.3), DirectionAt(-0.7, 0.3)}) {
      int produced = 0;
      for (const Scattered& s : SampleMany(*model, wi, 2000, 213, allowed)) {
        if (!(s.pdf > 0)) continue;
        ++produced;
        EXPECT_EQ(s.flags, allowed);
        EXPECT_EQ(wi.z * s.wo.z > 0, (allowed & kScatterReflect) != 0) << Describe(s.wo);
        EXPECT_TRUE(std::isfinite(s.weight.x) && s.weight.x >= 0) << Describe(s.weight);
      }
      // Every lobe scatters from both sides (a few glossy draws are lost
      // under the horizon).
      EXPECT_GT(produced, 2000 * 3 / 4) << allowed << ", wi " << Describe(wi);
    }
}

// --- Reciprocity and energy ----------------------------------------------------

TEST_F(PrincipledTest, ReflectionIsReciprocal) {
  for (const Variant& v : Variants()) {
    if (v.below) continue;
    const auto model = Make(v.model, v.props);
    for (uint64_t k = 0; k < 2000; ++k) {
      const auto u = Uniform3(205, k), w = Uniform3(206, k);
      const Vec3 a = SampleUniformSphere(u[0], u[1]), b = SampleUniformSphere(w[0], w[1]);
      const Vec3 f = EvaluateOne(*model, a, b);
      ExpectVecNear(f, EvaluateOne(*model, b, a), 1e-4f, v.name + ": f(a, b) vs f(b, a)");
      // Without the glass, nothing scatters below.
      if (a.z <= 0 || b.z <= 0) {
        ExpectVecNear(f, Vec3(), 0, v.name + " below");
      }
    }
  }
}

TEST_F(PrincipledTest, RefractionIsReciprocalBetweenRadianceAndImportance) {
  // f_radiance(a, b) = f_importance(b, a) (Veach 1997, §5.2).
  for (const Variant& v : Variants()) {
    if (!v.below) continue;
    const auto model = Make(v.model, v.props);
    for (uint64_t k = 0; k < 2000; ++k) {
      const auto u = Uniform3(207, k), w = Uniform3(208, k);
      const Vec3 a = SampleUniformSphere(u[0], u[1]), b = SampleUniformSphere(w[0], w[1]);
      ExpectVecNear(EvaluateOne(*model, a, b, kRadiance), EvaluateOne(*model, b, a, kImportance), 1e-4f,
                    v.name + ": radiance f(a, b) vs importance f(b, a)");
    }
  }
}

TEST_F(PrincipledTest, ThinSheetIsAlikeFromBothSides) {
  // The sheet has no inside: mirrored through it, wi and wo scatter as
  // before, and (one medium on both sides) importance as radiance.
  for (const Variant& v : Variants()) {
    if (v.model != "principledthin") continue;
    const auto model = Make(v.model, v.props);
    for (uint64_t k = 0; k < 2000; ++k) {
      const auto u = Uniform3(214, k), w = Uniform3(215, k);
      const Vec3 a = SampleUniformSphere(u[0], u[1]), b = SampleUniformSphere(w[0], w[1]);
      const Vec3 f = EvaluateOne(*model, a, b);
      const Vec3 a_mirror(a.x, a.y, -a.z), b_mirror(b.x, b.y, -b.z);
      ExpectVecNear(EvaluateOne(*model, a_mirror, b_mirror), f, 1e-4f, v.name + ": mirrored through the sheet");
      EXPECT_NEAR(PdfOne(*model, a_mirror, b_mirror), PdfOne(*model, a, b), 1e-4f * std::max(1.0f, PdfOne(*model, a, b)))
          << v.name;
      ExpectVecNear(EvaluateOne(*model, a, b, kImportance), f, 1e-6f, v.name + ": importance");
    }
  }
}

TEST_F(PrincipledTest, ReflectsNoMoreThanArrives) {
  // The albedo ∫ f |cos θo| dωo by quadrature and by Sample's mean weight,
  // in importance (refraction without 1/η², the energy that leaves).
  for (const Variant& v : Variants()) {
    const auto model = Make(v.model, v.props);
    for (Vec3 wi : Incident(v.below)) {
      const Vec3 quadrature = IntegrateOverSphere(*model, wi, kImportance).albedo;
      const MeanWithError sampled = MeanWeight(SampleMany(*model, wi, 50000, 209, 0, kImportance));
      const std::string where = v.name + ", wi " + Describe(wi) + ": albedo " + Describe(quadrature);
      EXPECT_LE(MaxComponent(quadrature), 1.0f + 3e-3f) << where;
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(sampled.mean[c], quadrature[c], 5 * sampled.standard_error[c] + 5e-3f) << where;
    }
  }
}

// --- Textured parameters -------------------------------------------------------

TEST_F(PrincipledTest, EveryParameterMayBeATexture) {
  // A material where every lobe is on, so that each parameter matters.
  ExpectTexturesActAsConstants(
      "principled",
      Props({{"spec_trans", 0.3}, {"clearcoat", 0.5}, {"sheen", 0.5}, {"metallic", 0.2}, {"spec_tint", 0.3},
             {"anisotropic", 0.3}, {"flatness", 0.3}, {"sheen_tint", 0.3}, {"roughness", 0.4},
             {"clearcoat_gloss", 0.3}}),
      {"base_color", "roughness", "anisotropic", "metallic", "spec_trans", "spec_tint", "sheen", "sheen_tint",
       "flatness", "clearcoat", "clearcoat_gloss"});
}

TEST_F(PrincipledTest, EveryThinParameterMayBeATexture) {
  ExpectTexturesActAsConstants(
      "principledthin",
      Props({{"spec_trans", 0.4}, {"diff_trans", 0.6}, {"sheen", 0.5}, {"spec_tint", 0.3}, {"anisotropic", 0.3},
             {"flatness", 0.3}, {"sheen_tint", 0.3}, {"roughness", 0.4}, {"eta", 1.4}}),
      {"base_color", "roughness", "anisotropic", "spec_trans", "diff_trans", "eta", "spec_tint", "sheen",
       "sheen_tint", "flatness"});
}

}  // namespace
}  // namespace yarf
