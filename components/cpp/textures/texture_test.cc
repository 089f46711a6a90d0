// Tests of the texture plugins (textures/*.cc), loaded through the
// registry as yarfd loads them, on images written here with OpenImageIO:
// the bitmap's reconstruction filters, wrap modes, decoding of 8-bit
// sRGB before filtering, MIP level selection from the footprint, uv maps,
// scale / invert and mean; the checkerboard's cells in Mitsuba's and
// pbrt's conventions and its box filter; mix, scale and constant; and
// the errors bad properties give.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "texture_test_support.h"
#include "yarf/texture.h"

namespace yarf {
namespace {

using namespace texture_testing;  // NOLINT: the shared helpers, in every test
using S = std::string;

// A 2×2 grey image: top row 1 2, bottom row 3 4.
const std::vector<float> kFour = {1, 2, 3, 4};

class BitmapTextureTest : public TexturePluginTest {
 protected:
  std::filesystem::path Four() const { return WriteImage("four.exr", 2, 2, 1, kFour); }
};

TEST_F(BitmapTextureTest, EveryTextureClassIsRegisteredAsATexture) {
  for (const PluginFailure& failure : registry_.Failures())
    EXPECT_EQ(failure.path.find("texture_"), std::string::npos) << failure.path << ": " << failure.message;
  for (const char* name : {"bitmap", "checkerboard", "scale", "mix", "constant_texture"}) {
    ASSERT_TRUE(registry_.Has(name)) << name;
    const auto info = registry_.Classes();
    for (const ComponentInfo& c : info)
      if (c.class_name == name) {
        EXPECT_EQ(c.interfaces, std::vector<std::string>{Texture::kInterface}) << name;
        EXPECT_FALSE(c.summary.empty()) << name;
      }
  }
}

TEST_F(BitmapTextureTest, BilinearIsExactAtTexelCentresAndBetweenThem) {
  const auto texture = MakeBitmap(Four());
  ASSERT_EQ(texture->Channels(), 1u);
  // v = 0 is the top row.
  EXPECT_FLOAT_EQ(At(*texture, 0.25f, 0.25f), 1);
  EXPECT_FLOAT_EQ(At(*texture, 0.75f, 0.25f), 2);
  EXPECT_FLOAT_EQ(At(*texture, 0.25f, 0.75f), 3);
  EXPECT_FLOAT_EQ(At(*texture, 0.75f, 0.75f), 4);
  EXPECT_FLOAT_EQ(At(*texture, 0.5f, 0.25f), 1.5f);
  EXPECT_FLOAT_EQ(At(*texture, 0.25f, 0.5f), 2);
  EXPECT_FLOAT_EQ(At(*texture, 0.5f, 0.5f), 2.5f);  // the mean of the four
  EXPECT_FLOAT_EQ(At(*texture, 0.375f, 0.25f), 1.25f);
  // Bilinear has no MIP map: a footprint does not blur it.
  EXPECT_FLOAT_EQ(At(*texture, 0.25f, 0.25f, {0.5f, 0, 0, 0.5f}), 1);
}

TEST_F(BitmapTextureTest, NearestGivesTheTexelContainingThePoint) {
  for (const S filter : {"nearest", "point"}) {
    const auto texture = MakeBitmap(Four(), With({{filter == "point" ? "filter" : "filter_type", filter}}));
    EXPECT_FLOAT_EQ(At(*texture, 0.49f, 0.01f), 1) << filter;
    EXPECT_FLOAT_EQ(At(*texture, 0.51f, 0.01f), 2) << filter;
    EXPECT_FLOAT_EQ(At(*texture, 0.1f, 0.6f), 3) << filter;
    EXPECT_FLOAT_EQ(At(*texture, 0.6f, 0.9f), 4) << filter;
  }
}

TEST_F(BitmapTextureTest, WrapModesRepeatMirrorClampAndBlack) {
  struct Case {
    S key, mode;
    float left, right, edge;  // at u = -0.75, 1.25 and 0 on the top row
  };
  for (const Case& c : {Case{"wrap_mode", "repeat", 1, 1, 1.5f}, Case{"wrap_mode", "mirror", 2, 2, 1},
                        Case{"wrap_mode", "clamp", 1, 2, 1}, Case{"wrap", "black", 0, 0, 0.5f},
                        Case{"wrap", "repeat", 1, 1, 1.5f}, Case{"wrap", "clamp", 1, 2, 1}}) {
    const auto texture = MakeBitmap(Four(), With({{c.key, c.mode}}));
    EXPECT_FLOAT_EQ(At(*texture, -0.75f, 0.25f), c.left) << c.mode;
    EXPECT_FLOAT_EQ(At(*texture, 1.25f, 0.25f), c.right) << c.mode;
    EXPECT_FLOAT_EQ(At(*texture, 0.0f, 0.25f), c.edge) << c.mode;
  }
  // The default repeats.
  EXPECT_FLOAT_EQ(At(*MakeBitmap(Four()), 1.25f, 1.25f), 1);
}

TEST_F(BitmapTextureTest, EightBitSrgbIsDecodedBeforeFiltering) {
  const double encoded = 188.0 / 255.0;
  const double linear = std::pow((encoded + 0.055) / 1.055, 2.4);
  ASSERT_NEAR(linear, 0.5029, 1e-4);
  const auto png = WriteImage("grey.png", 1, 1, 3, {float(encoded), float(encoded), float(encoded)}, OIIO::TypeUInt8);
  const auto decoded = MakeBitmap(png);
  ASSERT_EQ(decoded->Channels(), 3u);
  const std::vector<float> rgb = Lookup(*decoded, {0.5f, 0.5f});
  for (float c : rgb) EXPECT_NEAR(c, linear, 1e-5);
  EXPECT_NEAR(decoded->Mean()[1], linear, 1e-5);
  for (const auto& props : {With({{"raw", true}}), With({{"encoding", S("linear")}})})
    for (float c : Lookup(*MakeBitmap(png, props), {0.5f, 0.5f})) EXPECT_NEAR(c, encoded, 1e-6);
  for (float c : Lookup(*MakeBitmap(png, With({{"encoding", S("gamma 2.2")}})), {0.5f, 0.5f}))
    EXPECT_NEAR(c, std::pow(encoded, 2.2), 1e-5);

  // Black and white side by side: halfway is the mean of the linear
  // values (0.5), not the decoded mean of the bytes (about 0.21).
  const auto edge = WriteImage("edge.png", 2, 1, 1, {0.0f, 1.0f}, OIIO::TypeUInt8);
  EXPECT_NEAR(At(*MakeBitmap(edge, With({{"wrap_mode", S("clamp")}})), 0.5f, 0.5f), 0.5f, 1e-6);

  // A float image is linear: never decoded.
  const auto exr = WriteImage("grey.exr", 1, 1, 1, {float(encoded)});
  EXPECT_FLOAT_EQ(At(*MakeBitmap(exr), 0.5f, 0.5f), float(encoded));
}

TEST_F(BitmapTextureTest, FootprintSelectsTheMipLevel) {
  // A bright line two texels wide down the middle of a dark 64×64 image.
  // Level j is the box average of 2^j × 2^j texels, so at u = 1/2 (between
  // two of its texels) its bilinear value is the mean of the 2^(j+1)
  // columns around the middle: 2^-j, one value per level.
  constexpr int kSide = 64, kMiddle = kSide / 2;
  std::vector<float> texels(kSide * kSide, 0.0f);
  for (int y = 0; y < kSide; ++y) texels[y * kSide + kMiddle - 1] = texels[y * kSide + kMiddle] = 1;
  const auto file = WriteImage("line.exr", kSide, kSide, 1, texels);
  const auto level = [&](int j) {  // the box filter, done here
    const int half = 1 << j;
    float sum = 0;
    for (int x = kMiddle - half; x < kMiddle + half; ++x) sum += texels[x];
    return sum / float(2 * half);
  };
  ASSERT_FLOAT_EQ(level(2), 0.25f);
  // A footprint of `texels` texels along u and v, at the middle.
  const auto at_width = [&](const Texture& texture, float texels) {
    const float d = texels / kSide;
    return At(texture, 0.5f, 0.5f, {d, 0, 0, d});
  };
  for (const S filter : {"trilinear", "ewa"}) {
    const auto texture = MakeBitmap(file, With({{"filter_type", filter}}));
    EXPECT_NEAR(At(*texture, 0.5f, 0.5f), 1, 1e-6) << filter;
    EXPECT_NEAR(At(*texture, 0.25f, 0.5f), 0, 1e-6) << filter;
    EXPECT_NEAR(texture->Mean()[0], 2.0f / kSide, 1e-6) << filter;
    // A footprint of exactly 2^j texels reads level j alone.
    for (int j = 0; j <= 4; ++j) EXPECT_NEAR(at_width(*texture, float(1 << j)), level(j), 1e-5) << filter << j;
  }
  // Between two levels trilinear blends them, OpenImageIO's way: a width
  // of w·2^j texels, 1 < w < 2, weighs level j+1 by w − 1 (linear in the
  // width, where pbrt's log2 w would give 0.58 at w = 1.5).
  const auto trilinear = MakeBitmap(file, With({{"filter_type", S("trilinear")}}));
  for (int j = 0; j <= 3; ++j)
    for (const float w : {1.25f, 1.5f, 1.75f})
      EXPECT_NEAR(at_width(*trilinear, w * float(1 << j)), (2 - w) * level(j) + (w - 1) * level(j + 1), 1e-5)
          << "w = " << w << " · 2^" << j;
  // A footprint 1 texel across the line and 16 along it: trilinear takes
  // the level of the longer axis (level 4), ewa follows the line at the
  // level of the shorter one (level 0) when the anisotropy allows it.
  const std::array<float, 4> thin = {1.0f / kSide, 0, 0, 16.0f / kSide};
  EXPECT_NEAR(At(*trilinear, 0.5f, 0.5f, thin), level(4), 1e-5);
  const auto ewa = MakeBitmap(file, With({{"filter", S("ewa")}, {"maxanisotropy", 16.0}}));
  EXPECT_NEAR(At(*ewa, 0.5f, 0.5f, thin), level(0), 0.02f);
}

TEST_F(BitmapTextureTest, UvMapsMoveTheLookup) {
  // to_uv: u' = u/2 + 1/4, v' = v/2 + 1/4 (a 4×4 acting on (u, v, 0)).
  Transform half;
  half.m = {0.5, 0, 0, 0.25, 0, 0.5, 0, 0.25, 0, 0, 1, 0, 0, 0, 0, 1};
  const auto mapped = MakeBitmap(Four(), With({{"to_uv", half}}));
  EXPECT_FLOAT_EQ(At(*mapped, 0, 0), 1);
  EXPECT_FLOAT_EQ(At(*mapped, 1, 0), 2);
  EXPECT_FLOAT_EQ(At(*mapped, 1, 1), 4);
  // pbrt's form: u' = 2u + 0.5, v' = v/2 + 0.5.
  const auto scaled = MakeBitmap(
      Four(), With({{"uscale", 2.0}, {"udelta", 0.5}, {"vscale", 0.5}, {"vdelta", 0.5}, {"filter", S("point")}}));
  EXPECT_FLOAT_EQ(At(*scaled, 0.125f, 0.5f), 4);  // (0.75, 0.75)
  EXPECT_FLOAT_EQ(At(*scaled, 0.3f, 0.1f), 3);    // (1.1, 0.55) → (0.1, 0.55)
  EXPECT_NE(CreationError("bitmap", With({{"filename", Four()}, {"to_uv", half}, {"uscale", 2.0}})), "");
}

TEST_F(BitmapTextureTest, ScaleThenInvertAsPbrt) {
  const auto scaled = MakeBitmap(Four(), With({{"scale", 2.0}}));
  EXPECT_FLOAT_EQ(At(*scaled, 0.75f, 0.75f), 8);
  EXPECT_FLOAT_EQ(scaled->Mean()[0], 5);
  const auto inverted = MakeBitmap(Four(), With({{"scale", 0.5}, {"invert", true}}));
  EXPECT_FLOAT_EQ(At(*inverted, 0.25f, 0.25f), 0.5f);  // 1 − 0.5·1
  EXPECT_FLOAT_EQ(At(*inverted, 0.75f, 0.75f), 0);     // max(0, 1 − 0.5·4)
  EXPECT_FLOAT_EQ(inverted->Mean()[0], 0.125f);        // (0.5 + 0 + 0 + 0) / 4
}

TEST_F(BitmapTextureTest, RgbaGivesRgbAndItsMean) {
  const auto file = WriteImage("rgba.exr", 2, 1, 4, {0.1f, 0.2f, 0.3f, 1.0f, 0.3f, 0.4f, 0.5f, 0.0f});
  const auto texture = MakeBitmap(file, With({{"filter_type", S("nearest")}}));
  ASSERT_EQ(texture->Channels(), 3u);
  const std::vector<float> right = Lookup(*texture, {0.75f, 0.5f});
  EXPECT_FLOAT_EQ(right[0], 0.3f);
  EXPECT_FLOAT_EQ(right[2], 0.5f);
  const std::vector<float> mean = texture->Mean();
  ASSERT_EQ(mean.size(), 3u);
  EXPECT_FLOAT_EQ(mean[0], 0.2f);
  EXPECT_FLOAT_EQ(mean[1], 0.3f);
  EXPECT_FLOAT_EQ(mean[2], 0.4f);
  EXPECT_FLOAT_EQ(MakeBitmap(Four())->Mean()[0], 2.5f);
}

TEST_F(BitmapTextureTest, LookupsFromManyThreadsAgree) {
  const auto texture = MakeBitmap(Four(), With({{"filter_type", S("trilinear")}}));
  std::vector<float> uv;
  for (int k = 0; k < 2000; ++k) uv.insert(uv.end(), {k * 0.00137f, k * 0.00291f});
  const std::vector<float> expected = Lookup(*texture, uv);
  std::vector<std::vector<float>> got(4);
  std::vector<std::thread> threads;
  for (auto& g : got) threads.emplace_back([&] { g = Lookup(*texture, uv); });
  for (auto& t : threads) t.join();
  for (const auto& g : got) EXPECT_EQ(g, expected);
}

// TMPDIR at `folder` while it lives, and as it was after: tests running
// beside one another make and remove folders of the same names in the
// shared temporary folder.
class TemporaryFolderAt {
 public:
  explicit TemporaryFolderAt(const std::filesystem::path& folder) {
    if (const char* old = std::getenv("TMPDIR")) old_ = old;
    setenv("TMPDIR", folder.c_str(), 1);
  }
  ~TemporaryFolderAt() {
    if (old_) {
      setenv("TMPDIR", old_->c_str(), 1);
    } else {
      unsetenv("TMPDIR");
    }
  }
  TemporaryFolderAt(const TemporaryFolderAt&) = delete;
  TemporaryFolderAt& operator=(const TemporaryFolderAt&) = delete;

 private:
  std::optional<std::string> old_;
};

TEST_F(BitmapTextureTest, ItsTemporaryFolderGoesWithIt) {
  const TemporaryFolderAt own(folder_.path());
  const auto listing = [] {
    std::set<std::filesystem::path> out;
    for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::temp_directory_path()))
      if (entry.path().filename().string().rfind("yarf-bitmap-", 0) == 0) out.insert(entry.path());
    return out;
  };
  const auto before = listing();
  std::set<std::filesystem::path> made;
  {
    // Only a MIP-mapped filter writes its image to a file.
    const auto bilinear = MakeBitmap(Four());
    EXPECT_EQ(listing(), before);
    const auto texture = MakeBitmap(Four(), With({{"filter_type", S("trilinear")}}));
    for (const auto& p : listing())
      if (!before.count(p)) made.insert(p);
    EXPECT_EQ(made.size(), 1u);
  }
  for (const auto& p : made) EXPECT_FALSE(std::filesystem::exists(p)) << p;
}

// Nearest and bilinear are looked up in memory, trilinear by OpenImageIO:
// at a point footprint trilinear reads the full image bilinearly, so the
// two must agree under every wrap, inside the image and outside it.
TEST_F(BitmapTextureTest, BilinearInMemoryAgreesWithOpenImageIoUnderEveryWrap) {
  constexpr int kWidth = 5, kHeight = 3;
  std::vector<float> texels(kWidth * kHeight * 3);
  for (size_t i = 0; i < texels.size(); ++i) texels[i] = float((i * 7919) % 23) / 23.0f;
  const auto file = WriteImage("odd.exr", kWidth, kHeight, 3, texels);
  std::vector<float> uv;
  for (int i = 0; i < 400; ++i) uv.insert(uv.end(), {-2.3f + 0.0157f * float(i), 3.1f - 0.0163f * float(i)});
  for (const S wrap : {"repeat", "mirror", "clamp", "black"}) {
    const auto memory = Lookup(*MakeBitmap(file, With({{"wrap_mode", wrap}})), uv);
    const auto oiio = Lookup(*MakeBitmap(file, With({{"wrap_mode", wrap}, {"filter_type", S("trilinear")}})), uv);
    ASSERT_EQ(memory.size(), oiio.size());
    for (size_t k = 0; k < memory.size(); ++k) EXPECT_NEAR(memory[k], oiio[k], 1e-5) << wrap << " at " << k / 3;
  }
}

TEST_F(BitmapTextureTest, CoordinatesNotFiniteOrFarOffGiveFiniteValues) {
  for (const S filter : {"nearest", "bilinear"})
    for (const S wrap : {"repeat", "mirror", "clamp", "black"}) {
      const auto texture = MakeBitmap(Four(), With({{"filter_type", filter}, {"wrap_mode", wrap}}));
      const std::vector<float> values = Lookup(*texture, {NAN, 0.5f, 0.5f, INFINITY, 1e30f, -1e30f, -3e9f, 7e9f});
      EXPECT_EQ(values[0], 0) << filter << " " << wrap;
      EXPECT_EQ(values[1], 0) << filter << " " << wrap;
      for (float v : values) EXPECT_TRUE(v >= 0 && v <= 4) << filter << " " << wrap << ": " << v;
    }
}

TEST_F(BitmapTextureTest, BadPropertiesAndFilesGiveClearErrors) {
  const auto expect_error = [&](const Properties& props, const std::string& part) {
    const std::string message = CreationError("bitmap", props);
    EXPECT_NE(message.find(part), std::string::npos) << "'" << message << "' lacks '" << part << "'";
  };
  expect_error(With({{"filename", folder_.path() / "missing.png"}}), "'filename'");
  expect_error(With({{"filename", folder_.path() / "missing.png"}}), "does not exist");
  expect_error(With({{"filename", S("four.exr")}}), "'filename' must be of type file");
  expect_error(Properties(), "missing property 'filename'");
  const auto file = Four();
  expect_error(With({{"filename", file}, {"filter_type", S("cubic")}}), "'filter_type' must be one of");
  expect_error(With({{"filename", file}, {"filter", S("gaussian")}}), "'filter' must be one of");
  expect_error(With({{"filename", file}, {"wrap_mode", S("tile")}}), "'wrap_mode' must be one of");
  expect_error(With({{"filename", file}, {"wrap", S("octahedralsphere")}}), "octahedral");
  expect_error(With({{"filename", file}, {"encoding", S("gamma -1")}}), "'encoding'");
  expect_error(With({{"filename", file}, {"raw", true}, {"encoding", S("linear")}}), "'raw'");
  expect_error(With({{"filename", file}, {"scale", std::nan("")}}), "'scale'");
  expect_error(With({{"filename", file}, {"uscale", HUGE_VAL}}), "'uscale'");
  expect_error(With({{"filename", file}, {"filter_type", S("nearest")}, {"filter", S("point")}}), "two names");
  expect_error(With({{"filename", file}, {"colour", 1.0}}), "has no parameter 'colour'");
  const std::filesystem::path text = folder_.path() / "not_an_image.png";
  { std::ofstream(text) << "not an image"; }
  expect_error(With({{"filename", text}}), "cannot be read");
}

TEST_F(BitmapTextureTest, WrongArrayShapesAreRefused) {
  const auto texture = MakeBitmap(Four());
  std::vector<float> uv = {0.5f, 0.5f}, value(2), footprint(3);
  EXPECT_THROW(texture->Evaluate(SurfacePoints{uv, {}}, value), Error);
  value.resize(1);
  EXPECT_THROW(texture->Evaluate(SurfacePoints{uv, footprint}, value), Error);
}

// --- checkerboard ------------------------------------------------------------

class CheckerboardTextureTest : public TexturePluginTest {};

TEST_F(CheckerboardTextureTest, MitsubaCellsOverTheUnitSquare) {
  const auto texture = Make("checkerboard");  // color0 0.4, color1 0.2
  EXPECT_FLOAT_EQ(At(*texture, 0.25f, 0.25f), 0.4f);
  EXPECT_FLOAT_EQ(At(*texture, 0.75f, 0.25f), 0.2f);
  EXPECT_FLOAT_EQ(At(*texture, 0.25f, 0.75f), 0.2f);
  EXPECT_FLOAT_EQ(At(*texture, 0.75f, 0.75f), 0.4f);
  EXPECT_FLOAT_EQ(At(*texture, 1.25f, -0.75f), 0.4f);  // periodic
  EXPECT_FLOAT_EQ(At(*texture, 0.5f, 0.25f), 0.4f);    // frac(u) > ½ is the upper half
  EXPECT_FLOAT_EQ(texture->Mean()[0], 0.3f);
  // to_uv scales the pattern: 4 × 4 cells.
  Transform twice;
  twice.m = {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const auto finer = Make("checkerboard", With({{"to_uv", twice}, {"color0", Rgb{Vec3(1, 0, 0)}}}));
  EXPECT_FLOAT_EQ(Lookup(*finer, {0.1f, 0.1f})[0], 1);
  EXPECT_FLOAT_EQ(Lookup(*finer, {0.3f, 0.1f})[0], 0.2f);
  EXPECT_FLOAT_EQ(Lookup(*finer, {0.3f, 0.3f})[0], 1);
  EXPECT_NEAR(finer->Mean()[0], 0.6f, 1e-6);
}

TEST_F(CheckerboardTextureTest, PbrtCellsOfUnitSideInScaledUv) {
  // Default scale: the unit square is one tex1 cell.
  const auto one = Make("checkerboard", With({{"tex1", 0.9}}));
  EXPECT_FLOAT_EQ(At(*one, 0.5f, 0.5f), 0.9f);
  EXPECT_FLOAT_EQ(At(*one, 1.5f, 0.5f), 0);  // tex2 defaults to 0
  EXPECT_FLOAT_EQ(one->Mean()[0], 0.9f);
  const auto four = Make("checkerboard", With({{"uscale", 4.0}, {"vscale", 4.0}}));
  EXPECT_FLOAT_EQ(At(*four, 0.1f, 0.1f), 1);  // (0.4, 0.4): even
  EXPECT_FLOAT_EQ(At(*four, 0.3f, 0.1f), 0);  // (1.2, 0.4): odd
  EXPECT_FLOAT_EQ(At(*four, 0.3f, 0.3f), 1);
  EXPECT_FLOAT_EQ(At(*four, -0.1f, 0.1f), 0);  // (−0.4, 0.4): cell −1 is odd
  EXPECT_FLOAT_EQ(four->Mean()[0], 0.5f);
  // Three cells across, one down: a third of the square is tex2.
  const auto three = Make("checkerboard", With({{"uscale", 3.0}, {"tex2", 0.3}}));
  EXPECT_NEAR(three->Mean()[0], 2.0f / 3 + 0.1f, 1e-6);
  const auto shifted = Make("checkerboard", With({{"udelta", 1.0}}));
  EXPECT_FLOAT_EQ(At(*shifted, 0.5f, 0.5f), 0);
}

TEST_F(CheckerboardTextureTest, FootprintBoxFiltersInClosedForm) {
  const auto texture = Make("checkerboard", With({{"uscale", 4.0}, {"vscale", 4.0}}));
  // A footprint inside one cell keeps the cell's exact colour.
  EXPECT_EQ(At(*texture, 0.1f, 0.1f, {0.01f, 0, 0, 0.01f}), 1.0f);
  // A box 1.3 cells wide each way: against the box average of point lookups.
  const float u = 0.37f, v = 0.61f, r = 1.3f / 4;
  double sum = 0;
  constexpr int kGrid = 600;
  std::vector<float> uv;
  for (int i = 0; i < kGrid; ++i)
    for (int j = 0; j < kGrid; ++j)
      uv.insert(uv.end(), {u - r + 2 * r * (i + 0.5f) / kGrid, v - r + 2 * r * (j + 0.5f) / kGrid});
  const std::vector<float> points = Lookup(*texture, uv);
  for (size_t k = 0; k < points.size(); k += 3) sum += points[k];
  EXPECT_NEAR(At(*texture, u, v, {r, 0, 0, r}), sum / (kGrid * kGrid), 2e-3);
  // Far away at a grazing angle: within 1% of the mean, in both forms.
  EXPECT_NEAR(At(*texture, 0.37f, 0.61f, {30, 0, 0, 0.002f}), 0.5f, 0.005f);
  EXPECT_NEAR(At(*texture, 1234.37f, -77.61f, {40, 25, 10, 60}), 0.5f, 0.005f);
  const auto mitsuba = Make("checkerboard");
  EXPECT_NEAR(At(*mitsuba, 0.37f, 0.61f, {0.1f, 0, 12, 20}), 0.3f, 0.003f);
}

TEST_F(CheckerboardTextureTest, ColoursMayBeTextures) {
  const auto grey = Make("constant_texture", With({{"value", 0.9}}));
  const auto texture = Make("checkerboard", With({{"color0", grey}}));
  EXPECT_FLOAT_EQ(At(*texture, 0.25f, 0.25f), 0.9f);
  EXPECT_FLOAT_EQ(At(*texture, 0.75f, 0.25f), 0.2f);
  EXPECT_FLOAT_EQ(texture->Mean()[0], 0.55f);
}

TEST_F(CheckerboardTextureTest, MixedFormsAndBadNumbersAreRefused) {
  EXPECT_NE(CreationError("checkerboard", With({{"color0", 1.0}, {"tex2", 0.0}})).find("not both"), std::string::npos);
  EXPECT_NE(CreationError("checkerboard", With({{"uscale", std::nan("")}})).find("'uscale'"), std::string::npos);
  EXPECT_NE(CreationError("checkerboard", With({{"color1", HUGE_VAL}})).find("'color1'"), std::string::npos);
}

// --- scale, mix, constant ------------------------------------------------------

class CompositeTextureTest : public TexturePluginTest {};

TEST_F(CompositeTextureTest, ConstantIsItsValueEverywhere) {
  const auto texture = Make("constant_texture", With({{"value", Rgb{Vec3(0.1f, 0.2f, 0.3f)}}}));
  ASSERT_EQ(texture->Channels(), 3u);
  const std::vector<float> value = Lookup(*texture, {0.3f, 0.8f, -5.0f, 7.0f});
  EXPECT_EQ(value, (std::vector<float>{0.1f, 0.2f, 0.3f, 0.1f, 0.2f, 0.3f}));
  EXPECT_EQ(texture->Mean(), (std::vector<float>{0.1f, 0.2f, 0.3f}));
  EXPECT_EQ(Make("constant_texture")->Mean(), (std::vector<float>{1, 1, 1}));
}

TEST_F(CompositeTextureTest, ScaleMultipliesAndReadsAColourFactorAsItsLuminance) {
  const auto image = WriteImage("four.exr", 2, 2, 1, kFour);
  const auto bitmap = MakeBitmap(image);
  const auto texture = Make("scale", With({{"tex", bitmap}, {"scale", 0.5}}));
  ASSERT_EQ(texture->Channels(), 3u);
  EXPECT_EQ(Lookup(*texture, {0.75f, 0.75f}), (std::vector<float>{2, 2, 2}));
  EXPECT_FLOAT_EQ(texture->Mean()[2], 1.25f);
  const auto red = Make("constant_texture", With({{"value", Rgb{Vec3(1, 0, 0)}}}));
  const auto by_red = Make("scale", With({{"tex", Rgb{Vec3(1, 2, 3)}}, {"scale", red}}));
  const std::vector<float> value = Lookup(*by_red, {0.5f, 0.5f});
  EXPECT_FLOAT_EQ(value[0], 0.2126f);
  EXPECT_FLOAT_EQ(value[2], 3 * 0.2126f);
  EXPECT_FLOAT_EQ(by_red->Mean()[1], 2 * 0.2126f);
}

TEST_F(CompositeTextureTest, MixBlendsByAmount) {
  const auto texture = Make("mix", With({{"tex1", Rgb{Vec3(1, 0, 0)}}, {"tex2", Rgb{Vec3(0, 0, 1)}}, {"amount", 0.25}}));
  EXPECT_EQ(Lookup(*texture, {0.5f, 0.5f}), (std::vector<float>{0.75f, 0, 0.25f}));
  EXPECT_EQ(texture->Mean(), (std::vector<float>{0.75f, 0, 0.25f}));
  EXPECT_EQ(Make("mix")->Mean(), (std::vector<float>{0.5f, 0.5f, 0.5f}));  // 0 and 1 by ½
  // A textured amount: the 2×2 image scaled to [0.25, 1].
  const auto amount = MakeBitmap(WriteImage("four.exr", 2, 2, 1, kFour), With({{"scale", 0.25}}));
  const auto varying = Make("mix", With({{"tex1", 0.0}, {"tex2", 2.0}, {"amount", amount}}));
  EXPECT_FLOAT_EQ(At(*varying, 0.25f, 0.25f), 0.5f);
  EXPECT_FLOAT_EQ(At(*varying, 0.75f, 0.75f), 2.0f);
  EXPECT_FLOAT_EQ(varying->Mean()[0], 2 * 0.625f);
  EXPECT_NE(CreationError("mix", With({{"amount", std::nan("")}})).find("'amount'"), std::string::npos);
}

}  // namespace
}  // namespace yarf
