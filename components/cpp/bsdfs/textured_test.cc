// Tests of textured parameters of the surface plugins (bsdfs/*.cc): a
// colour or roughness given as a texture acts, at each point, exactly as
// the constant of the texture's value there; a texture's values out of a
// parameter's range are clamped; a reference to no texture is an Error.
// The fixture and the batch-call helpers are surface_test_support.h's.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "surface_test_support.h"
#include "yarf/surface.h"
#include "yarf/texture.h"

namespace yarf {
namespace {

using namespace surface_testing;  // NOLINT: the shared helpers, in every test

// A texture whose value at (u, v) a function gives.
class FunctionTexture final : public Texture {
 public:
  using Function = std::function<std::vector<float>(float u, float v)>;
  FunctionTexture(uint32_t channels, Function function)
      : channels_(channels), function_(std::move(function)) {}

  uint32_t Channels() const override { return channels_; }
  void Evaluate(const SurfacePoints& at, std::span<float> value) const override {
    for (size_t k = 0; k < at.Count(); ++k) {
      const std::vector<float> v = function_(at.uv[2 * k], at.uv[2 * k + 1]);
      std::copy(v.begin(), v.end(), value.begin() + channels_ * k);
    }
  }
  std::vector<float> Mean() const override { return function_(0.5f, 0.5f); }

  std::vector<float> At(float u, float v) const { return function_(u, v); }

 private:
  uint32_t channels_;
  Function function_;
};

std::shared_ptr<const FunctionTexture> ColourTexture(FunctionTexture::Function function) {
  return std::make_shared<const FunctionTexture>(3, std::move(function));
}
std::shared_ptr<const FunctionTexture> FloatTexture(std::function<float(float, float)> function) {
  return std::make_shared<const FunctionTexture>(
      1, [function](float u, float v) { return std::vector<float>{function(u, v)}; });
}

// (u, v, 1/4) scaled: a colour that differs at every point.
std::shared_ptr<const FunctionTexture> UvColour(float scale) {
  return ColourTexture([scale](float u, float v) {
    return std::vector<float>{scale * u, scale * v, scale * 0.25f};
  });
}

// Two cells: `left` where u < 1/2, `right` elsewhere.
std::shared_ptr<const FunctionTexture> TwoCells(float left, float right) {
  return FloatTexture([=](float u, float) { return u < 0.5f ? left : right; });
}

void SetTexture(Properties& props, const std::string& key,
                std::shared_ptr<const FunctionTexture> texture) {
  props.Set(key, std::shared_ptr<const Texture>(std::move(texture)));
}

// --- One batch of points, each with its own uv ---------------------------

struct Rows {
  std::vector<Vec3> wi, wo;
  std::vector<float> uv;  // [N,2]
  std::vector<std::array<float, 3>> uniform;

  size_t Count() const { return wi.size(); }
  // Row k alone.
  Rows Row(size_t k) const {
    return {{wi[k]}, {wo[k]}, {uv[2 * k], uv[2 * k + 1]}, {uniform[k]}};
  }
};

// Points spread over the unit square of uv, with directions above and
// below (transmission) and a glossy pair near the mirror direction.
Rows SpreadRows() {
  Rows rows;
  constexpr int kCount = 24;
  for (int k = 0; k < kCount; ++k) {
    const std::array<float, 3> u = Uniform3(17, k);
    const float cos_i = 0.2f + 0.75f * u[1];
    rows.wi.push_back(DirectionAt(k % 5 == 4 ? -cos_i : cos_i, 0.3 + 0.5 * k));
    const Vec3 mirror = Reflect(rows.wi.back());
    const Vec3 other = DirectionAt(k % 3 == 2 ? -0.6 : 0.5 + 0.4 * u[2], 2.0 + k);
    rows.wo.push_back(k % 2 == 0 ? Normalize(mirror + 0.1f * other) : other);
    rows.uv.push_back((k + 0.5f) / kCount);
    rows.uv.push_back(u[0]);
    rows.uniform.push_back(Uniform3(23, k));
  }
  return rows;
}

struct Results {
  std::vector<float> value, pdf, wo, weight, sample_pdf;
  std::vector<uint32_t> flags;
};

// Evaluate, Pdf and Sample of all rows, one call each.
Results CallAll(const SurfaceModel& model, const Rows& rows, uint32_t allowed = 0) {
  const size_t n = rows.Count();
  std::vector<float> wi(3 * n), wo(3 * n), uniform(3 * n);
  for (size_t k = 0; k < n; ++k) {
    rows.wi[k].Store(&wi[3 * k]);
    rows.wo[k].Store(&wo[3 * k]);
    std::copy(rows.uniform[k].begin(), rows.uniform[k].end(), &uniform[3 * k]);
  }
  Results r{std::vector<float>(3 * n), std::vector<float>(n), std::vector<float>(3 * n),
            std::vector<float>(3 * n), std::vector<float>(n), std::vector<uint32_t>(n)};
  model.Evaluate(TransportMode::kRadiance, wi, wo, SurfacePoints{.uv = rows.uv}, r.value);
  model.Pdf(wi, wo, SurfacePoints{.uv = rows.uv}, r.pdf);
  model.Sample(TransportMode::kRadiance, wi, SurfacePoints{.uv = rows.uv}, uniform, allowed, r.wo, r.weight,
               r.sample_pdf, r.flags);
  return r;
}

// Row k of `batch` is bit for bit `single` (a one-row result).
void ExpectRowEquals(const Results& batch, size_t k, const Results& single,
                     const std::string& what) {
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(batch.value[3 * k + c], single.value[c]) << what << " Evaluate, row " << k;
    EXPECT_EQ(batch.wo[3 * k + c], single.wo[c]) << what << " Sample wo, row " << k;
    EXPECT_EQ(batch.weight[3 * k + c], single.weight[c]) << what << " Sample weight, row " << k;
  }
  EXPECT_EQ(batch.pdf[k], single.pdf[0]) << what << " Pdf, row " << k;
  EXPECT_EQ(batch.sample_pdf[k], single.sample_pdf[0]) << what << " Sample pdf, row " << k;
  EXPECT_EQ(batch.flags[k], single.flags[0]) << what << " Sample flags, row " << k;
}

// A model, one of whose properties is a texture.
struct TexturedCase {
  std::string model, key;
  std::shared_ptr<const FunctionTexture> texture;
  Properties others;  // the model's other properties
};

class TexturedParameterTest : public SurfacePluginTest {
 protected:
  // The model with the texture, called on all rows at once, against the
  // model with the constant the texture has at each row's uv.
  void ExpectActsAsItsValueAtEachPoint(const TexturedCase& c, uint32_t allowed = 0) const {
    const std::string what = c.model + " " + c.key;
    const Rows rows = SpreadRows();
    Properties textured = c.others;
    SetTexture(textured, c.key, c.texture);
    const Results batch = CallAll(*Make(c.model, textured), rows, allowed);
    for (size_t k = 0; k < rows.Count(); ++k) {
      const std::vector<float> value = c.texture->At(rows.uv[2 * k], rows.uv[2 * k + 1]);
      Properties constant = c.others;
      if (value.size() == 3)
        constant.Set(c.key, Rgb{Vec3(value[0], value[1], value[2])});
      else
        constant.Set(c.key, double(value[0]));
      ExpectRowEquals(batch, k, CallAll(*Make(c.model, constant), rows.Row(k), allowed), what);
    }
  }
};

TEST_F(TexturedParameterTest, LambertianValueAndWeightAreTheTextureAtEachPoint) {
  Properties props;
  SetTexture(props, "reflectance", UvColour(1.0f));
  const auto model = Make("lambertian", props);
  const Rows rows = SpreadRows();
  const Results r = CallAll(*model, rows);
  for (size_t k = 0; k < rows.Count(); ++k) {
    if (!(rows.wi[k].z > 0)) continue;
    const Vec3 rho(rows.uv[2 * k], rows.uv[2 * k + 1], 0.25f);
    if (rows.wo[k].z > 0)
      ExpectVecNear(Vec3::Load(&r.value[3 * k]), rho * kInvPi, 1e-6f, "f = ρ(uv)/π");
    ExpectVecNear(Vec3::Load(&r.weight[3 * k]), rho, 1e-6f, "Sample weight = ρ(uv)");
  }
}

TEST_F(TexturedParameterTest, EveryColourActsAsItsValueAtEachPoint) {
  // Halved, so that each sums with the other lobe's default to at most 1.
  const auto colour = UvColour(0.5f);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"lambertian", "reflectance"},
      {"mirror", "reflectance"},
      {"conductor", "specular_reflectance"},
      {"roughconductor", "specular_reflectance"},
      {"phong", "diffuse_reflectance"},
      {"phong", "specular_reflectance"},
      {"plastic", "diffuse_reflectance"},
      {"plastic", "specular_reflectance"},
      {"roughplastic", "diffuse_reflectance"},
      {"roughplastic", "specular_reflectance"},
      {"diffusetransmission", "reflectance"},
      {"diffusetransmission", "transmittance"},
  };
  for (const auto& [model, key] : cases) ExpectActsAsItsValueAtEachPoint({model, key, colour, {}});
}

TEST_F(TexturedParameterTest, TexturedLobesAreSampledAloneAsTheConstants) {
  const auto colour = UvColour(0.5f);
  ExpectActsAsItsValueAtEachPoint({"phong", "specular_reflectance", colour, {}},
                                  kScatterReflect | kScatterGlossy);
  ExpectActsAsItsValueAtEachPoint({"plastic", "diffuse_reflectance", colour, {}},
                                  kScatterReflect | kScatterDiffuse);
  ExpectActsAsItsValueAtEachPoint({"diffusetransmission", "transmittance", colour, {}},
                                  kScatterRefract | kScatterDiffuse);
}

TEST_F(TexturedParameterTest, RoughnessTextureActsAsTheConstantAtEachPoint) {
  const auto cells = TwoCells(0.05f, 0.4f);
  ExpectActsAsItsValueAtEachPoint({"roughconductor", "alpha", cells, {}});
  ExpectActsAsItsValueAtEachPoint({"roughdielectric", "alpha", cells, {}});
  Properties anisotropic;
  anisotropic.Set("alpha_v", 0.2);
  ExpectActsAsItsValueAtEachPoint({"roughconductor", "alpha_u", cells, anisotropic});
  ExpectActsAsItsValueAtEachPoint({"roughdielectric", "alpha_u", cells, anisotropic});
  Properties given_u;
  given_u.Set("alpha_u", 0.3);
  ExpectActsAsItsValueAtEachPoint({"roughconductor", "alpha_v", cells, given_u});
  ExpectActsAsItsValueAtEachPoint({"phong", "exponent", TwoCells(5.0f, 200.0f), {}});
}

TEST_F(TexturedParameterTest, ConductorIndexTexturesActAsTheConstantsAtEachPoint) {
  // η from 0.2 to 2.2 and κ from 1 to 5 over uv: Fresnel factors of every tint.
  const auto eta = ColourTexture([](float u, float v) { return std::vector<float>{0.2f + 2 * u, 0.5f + v, 1.3f}; });
  const auto k = ColourTexture([](float u, float v) { return std::vector<float>{1 + 4 * v, 2 + u, 3.5f}; });
  Properties given_k, given_eta;
  given_k.Set("k", Rgb{Vec3(3, 2.5f, 2)});
  given_eta.Set("eta", Rgb{Vec3(0.3f, 0.9f, 1.1f)});
  for (const char* model : {"conductor", "roughconductor"}) {
    ExpectActsAsItsValueAtEachPoint({model, "eta", eta, given_k});
    ExpectActsAsItsValueAtEachPoint({model, "k", k, given_eta});
  }
}

TEST_F(TexturedParameterTest, RoughnessTextureChangesTheLobeBetweenCells) {
  Properties props;
  SetTexture(props, "alpha", TwoCells(0.05f, 0.4f));
  const auto model = Make("roughconductor", props);
  const Vec3 wi = DirectionAt(0.8, 0.0), wo = Reflect(wi);
  float in[6], out[6], value[6];
  const float uv[4] = {0.25f, 0.5f, 0.75f, 0.5f};
  for (int k = 0; k < 2; ++k) {
    wi.Store(&in[3 * k]);
    wo.Store(&out[3 * k]);
  }
  model->Evaluate(TransportMode::kRadiance, in, out, SurfacePoints{.uv = uv}, value);
  // Near the mirror direction the smoother cell's lobe is far higher.
  EXPECT_GT(value[0], 10.0f * value[3]);
}

TEST_F(TexturedParameterTest, TextureValuesOutOfRangeAreClamped) {
  // Reflectance to [0, 1].
  Properties bright;
  SetTexture(bright, "reflectance",
             ColourTexture([](float, float) { return std::vector<float>{1.5f, -0.5f, 0.5f}; }));
  const Vec3 f = EvaluateOne(*Make("lambertian", bright), Vec3(0, 0, 1), Vec3(0, 0, 1));
  ExpectVecNear(f, Vec3(1.0f, 0.0f, 0.5f) * kInvPi, 1e-7f, "clamped reflectance");

  // Roughness to the smallest α, as a constant below it is raised.
  Properties smooth, smallest;
  SetTexture(smooth, "alpha", TwoCells(0.0f, -1.0f));
  smallest.Set("alpha", 1e-7);
  const Vec3 wi = DirectionAt(0.7, 0.2), wo = Normalize(Reflect(wi) + Vec3(0.001f, 0, 0));
  for (const char* name : {"roughconductor", "roughdielectric"}) {
    EXPECT_EQ(EvaluateOne(*Make(name, smooth), wi, wo).x,
              EvaluateOne(*Make(name, smallest), wi, wo).x)
        << name;
    EXPECT_EQ(PdfOne(*Make(name, smooth), wi, wo), PdfOne(*Make(name, smallest), wi, wo)) << name;
  }

  // A textured lobe that sums with the other to more than 1: both are
  // scaled to sum to 1 in that channel, the others left as they are.
  Properties excess;
  SetTexture(excess, "reflectance",
             ColourTexture([](float, float) { return std::vector<float>{0.9f, 0.5f, 0.1f}; }));
  const auto textured = Make("diffusetransmission", excess);
  const Vec3 up(0, 0, 1), down(0, 0, -1);
  const float sum = 0.9f + 0.25f;
  ExpectVecNear(EvaluateOne(*textured, up, up), Vec3(0.9f / sum, 0.5f, 0.1f) * kInvPi, 1e-6f,
                "scaled reflectance");
  ExpectVecNear(EvaluateOne(*textured, up, down), Vec3(0.25f / sum, 0.25f, 0.25f) * kInvPi,
                1e-6f, "scaled transmittance");
  const MeanWithError albedo = MeanWeight(SampleMany(*textured, DirectionAt(0.6, 1.0), 4000, 5));
  EXPECT_LE(albedo.mean.x, 1.0f + 3 * albedo.standard_error.x);
}

TEST_F(TexturedParameterTest, ConstantPropertiesAreReadAsBefore) {
  // The constant path takes the value as it is given: f = ρ/π exactly.
  Properties props;
  props.Set("reflectance", Rgb{Vec3(0.3f, 0.6f, 0.9f)});
  const Vec3 f = EvaluateOne(*Make("lambertian", props), Vec3(0, 0, 1), Vec3(0, 0, 1));
  EXPECT_EQ(f.x, 0.3f * kInvPi);
  EXPECT_EQ(f.y, 0.6f * kInvPi);
  EXPECT_EQ(f.z, 0.9f * kInvPi);
  // And a constant's range is still checked when the model is made.
  Properties over;
  over.Set("reflectance", 1.5);
  EXPECT_NE(CreationError("lambertian", over).find("'reflectance' must lie in [0, 1]"),
            std::string::npos);
  Properties creates;
  creates.Set("diffuse_reflectance", 0.9);
  creates.Set("specular_reflectance", 0.2);
  EXPECT_NE(CreationError("phong", creates).find("create energy"), std::string::npos);
}

TEST_F(TexturedParameterTest, ReferenceToNoTextureIsAnError) {
  for (const auto& [model, key] : std::vector<std::pair<std::string, std::string>>{
           {"lambertian", "reflectance"}, {"phong", "exponent"}, {"roughconductor", "alpha"},
           {"roughdielectric", "alpha_u"}, {"plastic", "specular_reflectance"}}) {
    Properties props;
    props.Set(key, Reference{"wood"});
    if (key == "alpha_u") props.Set("alpha_v", 0.1);
    const std::string expected =
        "property '" + key + "' refers to 'wood', which is not a texture of the scene";
    EXPECT_NE(CreationError(model, props).find(expected), std::string::npos)
        << model << " " << key;
  }
}

TEST_F(TexturedParameterTest, TabulatedRoughnessMustBeANumber) {
  Properties props;
  SetTexture(props, "alpha", TwoCells(0.1f, 0.2f));
  EXPECT_NE(CreationError("roughplastic", props).find("'alpha' must be a number"),
            std::string::npos);
}

}  // namespace
}  // namespace yarf
