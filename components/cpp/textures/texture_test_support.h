// What the texture tests (texture_test.cc) share: a fixture that loads
// the plugins as yarfd does, a private folder for the images a test
// writes with OpenImageIO, and one-call lookups of a few points.
#pragma once

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "components/registry.h"
#include "temporary_folder.h"
#include "yarf/texture.h"

namespace yarf::texture_testing {

class TexturePluginTest : public testing::Test {
 protected:
  TexturePluginTest() : folder_("yarf-texture-test") { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  std::shared_ptr<const Texture> Make(const std::string& name, const Properties& props = Properties()) const {
    return registry_.CreateAs<Texture>(name, props);
  }

  // The message of the Error that creating `name` with `props` throws ("" if none).
  std::string CreationError(const std::string& name, const Properties& props) const {
    try {
      registry_.Create(name, props);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }

  // Writes `texels` (row by row from the top, `channels` per texel) to
  // `name` in the test's folder, stored as `format`; returns its path.
  std::filesystem::path WriteImage(const std::string& name, int width, int height, int channels,
                                   const std::vector<float>& texels,
                                   OIIO::TypeDesc format = OIIO::TypeFloat) const {
    const std::filesystem::path path = folder_.path() / name;
    auto out = OIIO::ImageOutput::create(path.string());
    EXPECT_TRUE(out) << OIIO::geterror();
    if (!out) return path;
    const OIIO::ImageSpec spec(width, height, channels, format);
    EXPECT_TRUE(out->open(path.string(), spec)) << out->geterror();
    EXPECT_TRUE(out->write_image(OIIO::TypeFloat, texels.data())) << out->geterror();
    out->close();
    return path;
  }

  // The bitmap of `file` with the given further properties.
  std::shared_ptr<const Texture> MakeBitmap(const std::filesystem::path& file, Properties props = Properties()) const {
    props.Set("filename", file);
    return Make("bitmap", props);
  }

  Registry registry_;  // first: the textures' code lives in its plugins
  textures::TemporaryFolder folder_;
};

// The values of `texture` at the points `uv` ([N,2]) with `footprint`
// ([N,4] or empty), [N, Channels()].
inline std::vector<float> Lookup(const Texture& texture, const std::vector<float>& uv,
                                 const std::vector<float>& footprint = {}) {
  std::vector<float> value(uv.size() / 2 * texture.Channels());
  texture.Evaluate(SurfacePoints{uv, footprint}, value);
  return value;
}

// The first channel at one point.
inline float At(const Texture& texture, float u, float v, std::array<float, 4> footprint = {0, 0, 0, 0}) {
  return Lookup(texture, {u, v}, {footprint.begin(), footprint.end()})[0];
}

inline Properties With(std::initializer_list<std::pair<std::string, Properties::Value>> values) {
  Properties props;
  for (const auto& [key, value] : values) props.Set(key, value);
  return props;
}

}  // namespace yarf::texture_testing
