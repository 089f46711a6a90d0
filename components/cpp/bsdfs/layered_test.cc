// Tests of the layered surface plugins (coateddiffuse, coatedconductor;
// layered.h), loaded through the registry as yarfd loads them. Their f is
// a stochastic estimate seeded by a hash of (wi, wo, uv), so the tests
// compare means with their standard errors instead of single values:
// energy (a white furnace, and albedo ≤ 1 over parameter sets), the black
// base reducing to the coat's own reflection, reciprocity in expectation,
// Sample's pdf being Pdf's, the mean of Sample's weights being the albedo
// ∫ f |cos θo| dωo (the unbiasedness MIS relies on; a χ² test of a
// stochastic density would not apply), and property checking.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <iostream>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "surface_test_support.h"
#include "yarf/texture.h"
#include "yarf/surface.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

using namespace surface_testing;  // NOLINT: the shared helpers, in every test

constexpr TransportMode kRadiance = TransportMode::kRadiance;

struct Variant {
  std::string model, name;
  Properties props;
};

// Parameter sets of both models: smooth and rough coats, clear and
// scattering slabs, smooth and rough metals.
std::vector<Variant> Variants() {
  return {
      {"coateddiffuse", "default", Properties()},
      {"coateddiffuse", "rough", Props({{"roughness", 0.2}, {"reflectance", Rgb{Vec3(0.9f, 0.5f, 0.1f)}}})},
      {"coateddiffuse", "anisotropic", Props({{"uroughness", 0.05}, {"vroughness", 0.3}, {"eta", 1.33}})},
      {"coateddiffuse", "medium",
       Props({{"roughness", 0.1}, {"thickness", 0.5}, {"albedo", Rgb{Vec3(0.9f, 0.6f, 0.3f)}}, {"g", 0.5}})},
      {"coateddiffuse", "white", Props({{"reflectance", 1.0}, {"albedo", 1.0}, {"thickness", 1.0}, {"g", -0.3}})},
      {"coatedconductor", "default", Properties()},
      {"coatedconductor", "rough",
       Props({{"interface.roughness", 0.1}, {"conductor.roughness", 0.2}})},
      {"coatedconductor", "smooth coat", Props({{"conductor.roughness", 0.3}, {"interface.eta", 1.7}})},
      {"coatedconductor", "reflectance",
       Props({{"interface.roughness", 0.3}, {"reflectance", Rgb{Vec3(1.0f, 0.9f, 0.6f)}}, {"remaproughness", false},
              {"conductor.roughness", 0.3}})},
      {"coatedconductor", "medium",
       Props({{"interface.roughness", 0.2}, {"conductor.roughness", 0.1}, {"thickness", 0.3}, {"albedo", 0.8}})},
  };
}

std::vector<Vec3> Incident() {
  return {Vec3(0, 0, 1), DirectionAt(0.7, 0.4), DirectionAt(0.3, -1.2), DirectionAt(0.1, 2.5)};
}

// A mean and its standard error, per channel.
struct Estimate {
  Vec3 mean, error;
};

// ∫ f |cos θo| dωo over the upper hemisphere by the midpoint rule in
// (cos θ, φ): each node a different hash seed of f, so the sum also
// averages the estimator's noise; `error` treats the nodes as
// independent draws (an upper bound for a stratified grid).
Estimate QuadratureAlbedo(const SurfaceModel& model, Vec3 wi, int rows = 128, int cols = 256) {
  std::vector<Vec3> directions;
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      directions.push_back(DirectionAt((i + 0.5) / rows, 2 * kPiDouble * (j + 0.5) / cols));
  const std::vector<Vec3> values = EvaluateBatch(model, wi, directions, kRadiance);
  double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
  const double n = double(directions.size());
  for (size_t k = 0; k < directions.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      const double x = 2 * kPiDouble * values[k][c] * directions[k].z;  // f cos / uniform pdf
      sum[c] += x;
      sum2[c] += x * x;
    }
  Estimate out;
  float mean[3], error[3];
  for (int c = 0; c < 3; ++c) {
    mean[c] = float(sum[c] / n);
    error[c] = float(std::sqrt(std::max(0.0, sum2[c] / n - mean[c] * double(mean[c])) / n));
  }
  return {Vec3::Load(mean), Vec3::Load(error)};
}

// The part of the albedo in a smooth coat's delta reflection (not in
// Evaluate): the coat's Fresnel factor.
float DeltaAlbedo(const Variant& v, Vec3 wi) {
  const bool diffuse = v.model == "coateddiffuse";
  const std::string prefix = diffuse ? "" : "interface.";
  if (v.props.Has(prefix + "roughness") || v.props.Has(prefix + "uroughness")) return 0.0f;
  return FresnelDielectric(std::abs(wi.z), float(v.props.Float(diffuse ? "eta" : "interface.eta", 1.5)));
}

Estimate SampledAlbedo(const SurfaceModel& model, Vec3 wi, int count, uint64_t seed) {
  const MeanWithError m = MeanWeight(SampleMany(model, wi, count, seed));
  return {m.mean, m.standard_error};
}

// A texture of one value everywhere (1 or 3 channels).
class ConstantTexture final : public Texture {
 public:
  explicit ConstantTexture(std::vector<float> value) : value_(std::move(value)) {}
  uint32_t Channels() const override { return uint32_t(value_.size()); }
  void Evaluate(const SurfacePoints& at, std::span<float> value) const override {
    for (size_t k = 0; k < at.Count(); ++k) std::copy(value_.begin(), value_.end(), value.begin() + value_.size() * k);
  }
  std::vector<float> Mean() const override { return value_; }

 private:
  std::vector<float> value_;
};

class LayeredTest : public SurfacePluginTest {};

TEST_F(LayeredTest, RegistersBothModels) {
  ASSERT_NO_FATAL_FAILURE(ExpectRegisteredSurfaceModel("coateddiffuse"));
  ASSERT_NO_FATAL_FAILURE(ExpectRegisteredSurfaceModel("coatedconductor"));
}

// The fraction of the light arriving from `from` (wi, in importance
// mode: flux) that a rough dielectric reflects and transmits.
struct Split {
  double reflected = 0, transmitted = 0;
};

Split SplitFlux(const SurfaceModel& interface, const std::vector<Vec3>& from, uint64_t seed) {
  std::vector<std::array<float, 3>> uniform(from.size());
  for (size_t k = 0; k < from.size(); ++k) uniform[k] = Uniform3(seed, k);
  Split split;
  for (const Scattered& s : SampleBatch(interface, from, uniform, 0, TransportMode::kImportance))
    (s.flags & kScatterReflect ? split.reflected : split.transmitted) += s.weight.x / double(from.size());
  return split;
}

// A white base under a lossless coat (a clear, thin slab; walks long
// enough to let all the light out). A smooth coat reflects everything. A
// rough one loses what its microfacets' single scattering drops at each
// crossing: with R, T its reflected and transmitted flux at wi, and r, t
// those of the light the white base sends up to it (cosine-distributed,
// from inside), the albedo is R + T t / (1 - r), which roughdielectric (the
// same interface) gives.
TEST_F(LayeredTest, WhiteFurnace) {
  for (double roughness : {0.0, 0.005, 0.05}) {
    const auto model = Make("coateddiffuse", Props({{"reflectance", 1.0},
                                                    {"roughness", roughness},
                                                    {"thickness", 1e-5},
                                                    {"maxdepth", int64_t(200)}}));
    double inside_r = 0, inside_t = 0;
    std::unique_ptr<SurfaceModel> interface;
    if (roughness > 0) {
      interface = Make("roughdielectric", Props({{"alpha", std::sqrt(roughness)}, {"int_ior", 1.5}, {"ext_ior", 1.0}}));
      std::vector<Vec3> from_base(200000);
      for (size_t k = 0; k < from_base.size(); ++k) {
        const auto u = Uniform3(61, k);
        from_base[k] = -SampleCosineHemisphere(u[0], u[1]);  // light travelling up
      }
      const Split inside = SplitFlux(*interface, from_base, 62);
      inside_r = inside.reflected, inside_t = inside.transmitted;
    }
    for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.5, 0.3), DirectionAt(0.2, 1.0)}) {
      const std::string where = "roughness " + std::to_string(roughness) + " wi " + Describe(wi);
      const Estimate sampled = SampledAlbedo(*model, wi, 200000, 7);
      const Estimate quadrature = QuadratureAlbedo(*model, wi, 256, 512);
      const float delta = roughness == 0 ? FresnelDielectric(wi.z, 1.5f) : 0.0f;
      double expected = 1.0;
      if (roughness > 0) {
        const Split outside = SplitFlux(*interface, std::vector<Vec3>(200000, wi), 63);
        expected = outside.reflected + outside.transmitted * inside_t / (1.0 - inside_r);
      }
      std::cout << where << ": sampled " << sampled.mean.x << " ± " << sampled.error.x << ", quadrature "
                << quadrature.mean.x + delta << " ± " << quadrature.error.x << ", expected " << expected << "\n";
      EXPECT_NEAR(sampled.mean.x, expected, 4 * sampled.error.x + 3e-3) << where;
      EXPECT_NEAR(quadrature.mean.x + delta, expected, 4 * quadrature.error.x + 3e-3) << where;
    }
  }
}

// Energy: no parameter set reflects more than arrives, by Sample's mean
// weight and by quadrature.
TEST_F(LayeredTest, AlbedoIsAtMostOne) {
  for (const Variant& v : Variants()) {
    const auto model = Make(v.model, v.props);
    for (Vec3 wi : Incident()) {
      const std::string where = v.model + " " + v.name + " wi " + Describe(wi);
      const Estimate sampled = SampledAlbedo(*model, wi, 40000, 11);
      const Estimate quadrature = QuadratureAlbedo(*model, wi, 64, 128);
      for (int c = 0; c < 3; ++c) {
        EXPECT_LE(sampled.mean[c], 1.0f + 4 * sampled.error[c]) << where << " channel " << c;
        EXPECT_LE(quadrature.mean[c] + DeltaAlbedo(v, wi), 1.0f + 4 * quadrature.error[c] + 5e-3f)
            << where << " channel " << c;
      }
    }
  }
}

// With a black base and a clear slab nothing comes back from under the
// coat: coateddiffuse is the rough interface's reflection, which
// roughdielectric gives at α = √roughness.
TEST_F(LayeredTest, BlackBaseIsTheCoatsReflection) {
  for (double roughness : {0.04, 0.25}) {
    const auto coated = Make("coateddiffuse", Props({{"reflectance", 0.0}, {"roughness", roughness}, {"eta", 1.5}}));
    const auto interface =
        Make("roughdielectric", Props({{"alpha", std::sqrt(roughness)}, {"int_ior", 1.5}, {"ext_ior", 1.0}}));
    for (Vec3 wi : Incident())
      for (int k = 0; k < 200; ++k) {
        const Vec3 wo = SampleUniformHemisphere(Uniform3(21, k)[0], Uniform3(21, k)[1]);
        const Vec3 expected = EvaluateOne(*interface, wi, wo);
        const Vec3 below = EvaluateOne(*coated, -wi, -wo);  // two-sided
        ExpectVecNear(EvaluateOne(*coated, wi, wo), expected, 1e-4f, "wi " + Describe(wi) + " wo " + Describe(wo));
        ExpectVecNear(below, expected, 1e-4f, "below: wi " + Describe(wi) + " wo " + Describe(wo));
      }
  }
}

// f(wi, wo) and f(wo, wi) have one mean over the hash's seeds (different
// uv at each call).
TEST_F(LayeredTest, IsReciprocalInExpectation) {
  constexpr int kCalls = 20000;
  for (const Variant& v : Variants()) {
    const auto model = Make(v.model, v.props);
    for (auto [a, b] : std::vector<std::pair<Vec3, Vec3>>{{DirectionAt(0.9, 0.2), DirectionAt(0.4, 2.0)},
                                                          {DirectionAt(0.2, -1.0), DirectionAt(0.6, 0.5)}}) {
      std::vector<float> forward_in(3 * kCalls), backward_in(3 * kCalls), uv(2 * kCalls), value(3 * kCalls);
      std::vector<float> forward_out(3 * kCalls), backward_out(3 * kCalls), back_value(3 * kCalls);
      for (int k = 0; k < kCalls; ++k) {
        a.Store(&forward_in[3 * k]);
        b.Store(&forward_out[3 * k]);
        b.Store(&backward_in[3 * k]);
        a.Store(&backward_out[3 * k]);
        uv[2 * k] = (k + 0.5f) / kCalls;
        uv[2 * k + 1] = 0.25f;
      }
      model->Evaluate(kRadiance, forward_in, forward_out, SurfacePoints{.uv = uv}, value);
      model->Evaluate(kRadiance, backward_in, backward_out, SurfacePoints{.uv = uv}, back_value);
      for (int c = 0; c < 3; ++c) {
        double s1 = 0, s2 = 0, t1 = 0, t2 = 0;
        for (int k = 0; k < kCalls; ++k) {
          s1 += value[3 * k + c], s2 += double(value[3 * k + c]) * value[3 * k + c];
          t1 += back_value[3 * k + c], t2 += double(back_value[3 * k + c]) * back_value[3 * k + c];
        }
        const double m1 = s1 / kCalls, m2 = t1 / kCalls;
        const double e = std::sqrt((s2 / kCalls - m1 * m1 + t2 / kCalls - m2 * m2) / kCalls);
        EXPECT_NEAR(m1, m2, 4.5 * e + 1e-4 * std::max(m1, m2))
            << v.model << " " << v.name << " channel " << c << " " << Describe(a) << " ↔ " << Describe(b);
      }
    }
  }
}

// Sample's pdf is Pdf at the drawn direction (so MIS weighs both
// strategies with one density), > 0 wherever Sample lands; its flags are
// among Lobes; it only reflects, on wi's side (two-sided).
TEST_F(LayeredTest, SampleAgreesWithPdf) {
  for (const Variant& v : Variants()) {
    const auto model = Make(v.model, v.props);
    for (Vec3 wi : Incident())
      for (Vec3 side : {wi, -wi}) {
        int produced = 0;
        for (const Scattered& s : SampleMany(*model, side, 2000, 31)) {
          const std::string where = v.model + " " + v.name + " wi " + Describe(side) + " wo " + Describe(s.wo);
          if (!(s.pdf > 0)) {
            EXPECT_EQ(s.flags, uint32_t(kScatterNone)) << where;
            continue;
          }
          ++produced;
          EXPECT_EQ(s.flags & ~model->Lobes(), 0u) << where;
          EXPECT_TRUE(s.flags & kScatterReflect) << where;
          EXPECT_GT(side.z * s.wo.z, 0.0f) << where;
          EXPECT_NEAR(Length(s.wo), 1.0f, 1e-4f) << where;
          EXPECT_TRUE(std::isfinite(s.weight.x) && s.weight.x >= 0) << where;
          if (s.flags & kScatterDelta) continue;
          EXPECT_EQ(s.pdf, PdfOne(*model, side, s.wo)) << where;
          EXPECT_GT(MaxComponent(EvaluateOne(*model, side, s.wo)) + s.pdf, 0.0f) << where;
        }
        EXPECT_GT(produced, 2000 / 4) << v.model << " " << v.name << " wi " << Describe(side);
      }
    // Nothing is transmitted.
    for (Vec3 wi : Incident()) {
      EXPECT_EQ(PdfOne(*model, wi, -wi), 0.0f);
      ExpectVecNear(EvaluateOne(*model, wi, -wi), Vec3(), 0, v.model + " " + v.name + " transmitted");
    }
  }
}

// The mean of Sample's weight is the albedo ∫ f |cos θo| dωo (plus a
// smooth coat's delta reflection): Sample's weight is an unbiased estimate
// whatever density Pdf reports.
TEST_F(LayeredTest, MeanSampleWeightIsTheQuadratureAlbedo) {
  for (const Variant& v : Variants()) {
    const auto model = Make(v.model, v.props);
    // All delta paths (SmoothCoatedMetalIsDelta): nothing to integrate.
    if (model->Lobes() == (kScatterReflect | kScatterDelta)) continue;
    for (Vec3 wi : {Vec3(0, 0, 1), DirectionAt(0.4, 1.1)}) {
      const Estimate sampled = SampledAlbedo(*model, wi, 100000, 41);
      const Estimate quadrature = QuadratureAlbedo(*model, wi);
      const float delta = DeltaAlbedo(v, wi);
      for (int c = 0; c < 3; ++c) {
        const float integral = quadrature.mean[c] + delta;
        EXPECT_NEAR(sampled.mean[c], integral, 4 * std::hypot(sampled.error[c], quadrature.error[c]) + 5e-3f)
            << v.model << " " << v.name << " wi " << Describe(wi) << " channel " << c;
      }
    }
  }
}

// A smooth metal under a smooth coat and a clear slab is all delta paths:
// no value, no density, and Sample's weights still conserve energy.
TEST_F(LayeredTest, SmoothCoatedMetalIsDelta) {
  const auto model = Make("coatedconductor", Props({{"reflectance", 1.0}, {"thickness", 1e-5}, {"maxdepth", int64_t(100)}}));
  EXPECT_EQ(model->Lobes(), uint32_t(kScatterReflect | kScatterDelta));
  const Vec3 wi = DirectionAt(0.6, 0.3);
  EXPECT_EQ(PdfOne(*model, wi, Vec3(-wi.x, -wi.y, wi.z)), 0.0f);
  for (const Scattered& s : SampleMany(*model, wi, 1000, 51)) {
    if (!(s.pdf > 0)) continue;
    EXPECT_EQ(s.flags, uint32_t(kScatterReflect | kScatterDelta));
    ExpectVecNear(s.wo, Vec3(-wi.x, -wi.y, wi.z), 1e-4f, "mirror direction");
  }
  const Estimate sampled = SampledAlbedo(*model, wi, 20000, 52);
  EXPECT_NEAR(sampled.mean.x, 1.0f, 4 * sampled.error.x + 2e-3f);
}

// Every parameter pbrt lets be a texture may be one here: a model whose
// parameters are textures of the same values as a constant model's gives,
// call for call (the same hash seeds), the same Evaluate, Pdf and Sample.
TEST_F(LayeredTest, TexturedParametersMatchTheirConstants) {
  struct Parameter {
    const char* key;
    double value;
    bool colour;
  };
  const std::vector<std::pair<std::string, std::vector<Parameter>>> cases = {
      {"coateddiffuse",
       {{"reflectance", 0.6, true}, {"roughness", 0.1, false}, {"thickness", 0.3, false}, {"albedo", 0.5, true},
        {"g", 0.3, false}}},
      {"coatedconductor",
       {{"interface.roughness", 0.05, false}, {"conductor.roughness", 0.2, false}, {"conductor.eta", 0.3, true},
        {"conductor.k", 3.0, true}, {"thickness", 0.2, false}, {"albedo", 0.4, true}, {"g", -0.2, false}}},
      {"coatedconductor",
       {{"reflectance", 0.8, true}, {"interface.uroughness", 0.05, false}, {"interface.vroughness", 0.2, false},
        {"conductor.roughness", 0.1, false}}},
  };
  for (const auto& [name, parameters] : cases) {
    Properties constants, with_textures;
    for (const Parameter& p : parameters) {
      constants.Set(p.key, p.value);
      const float x = float(p.value);
      with_textures.Set(p.key, std::shared_ptr<const Texture>(std::make_shared<const ConstantTexture>(
                                   p.colour ? std::vector<float>{x, x, x} : std::vector<float>{x})));
    }
    const auto constant = Make(name, constants);
    const auto model = Make(name, with_textures);
    constexpr int kCount = 64;
    std::vector<float> wi(3 * kCount), wo(3 * kCount), uv(2 * kCount), u(3 * kCount);
    for (int k = 0; k < kCount; ++k) {
      const auto r = Uniform3(71, k);
      SampleCosineHemisphere(r[0], r[1]).Store(&wi[3 * k]);
      SampleCosineHemisphere(r[2], r[0]).Store(&wo[3 * k]);
      uv[2 * k] = r[1], uv[2 * k + 1] = r[2];
      std::copy(r.begin(), r.end(), &u[3 * k]);
    }
    const SurfacePoints at{.uv = uv};
    std::vector<float> a(3 * kCount), b(3 * kCount), pa(kCount), pb(kCount), oa(3 * kCount), ob(3 * kCount);
    std::vector<float> wa(3 * kCount), wb(3 * kCount), sa(kCount), sb(kCount);
    std::vector<uint32_t> fa(kCount), fb(kCount);
    constant->Evaluate(kRadiance, wi, wo, at, a);
    model->Evaluate(kRadiance, wi, wo, at, b);
    constant->Pdf(wi, wo, at, pa);
    model->Pdf(wi, wo, at, pb);
    constant->Sample(kRadiance, wi, at, u, 0, oa, wa, sa, fa);
    model->Sample(kRadiance, wi, at, u, 0, ob, wb, sb, fb);
    EXPECT_EQ(a, b) << name;
    EXPECT_EQ(pa, pb) << name;
    EXPECT_EQ(oa, ob) << name;
    EXPECT_EQ(wa, wb) << name;
    EXPECT_EQ(sa, sb) << name;
    EXPECT_EQ(fa, fb) << name;
    EXPECT_EQ(model->Lobes() & constant->Lobes(), constant->Lobes()) << name;  // textures: more may be possible
  }
}

TEST_F(LayeredTest, RefusesBadPropertiesByName) {
  const std::vector<std::tuple<std::string, Properties, std::string>> cases = {
      {"coateddiffuse", Props({{"thickness", 0.0}}), "thickness"},
      {"coateddiffuse", Props({{"g", 1.0}}), "'g'"},
      {"coateddiffuse", Props({{"eta", -1.5}}), "eta"},
      {"coateddiffuse", Props({{"roughness", -0.1}}), "roughness"},
      {"coateddiffuse", Props({{"vroughness", -0.1}}), "vroughness"},
      {"coateddiffuse", Props({{"maxdepth", int64_t(0)}}), "maxdepth"},
      {"coateddiffuse", Props({{"nsamples", int64_t(0)}}), "nsamples"},
      {"coateddiffuse", Props({{"reflectance", 1.5}}), "reflectance"},
      {"coateddiffuse", Props({{"albedo", -0.5}}), "albedo"},
      {"coateddiffuse", Props({{"alpha", 0.1}}), "alpha"},
      {"coatedconductor", Props({{"interface.eta", 0.0}}), "interface.eta"},
      {"coatedconductor", Props({{"conductor.k", -1.0}}), "conductor.k"},
      {"coatedconductor", Props({{"conductor.eta", 0.0}, {"conductor.k", 0.0}}), "conductor.eta"},
      {"coatedconductor", Props({{"reflectance", 0.5}, {"conductor.eta", 1.0}}), "reflectance"},
      {"coatedconductor", Props({{"conductor.roughness", -1.0}}), "conductor.roughness"},
      {"coatedconductor", Props({{"eta", 1.5}}), "eta"},
  };
  for (const auto& [model, props, name] : cases) {
    const std::string message = CreationError(model, props);
    EXPECT_NE(message.find(name), std::string::npos) << model << ": '" << message << "' should name " << name;
  }
}

}  // namespace
}  // namespace yarf
