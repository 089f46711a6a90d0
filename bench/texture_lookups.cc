// Texture lookups per second through yarf's `bitmap` (the Texture
// interface, batches of points, as surface models make them) against
// OpenImageIO's TextureSystem called directly, one point at a time, on
// the same MIP-mapped image with the same uv and footprints, for two
// filters: trilinear, which bitmap hands to OIIO (the cost of the
// component in front of it), and bilinear without a MIP map (Mitsuba's and
// pbrt's default), which bitmap looks up in memory. Prints JSON.
//
// usage: texture_lookups [lookups]

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/texture.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "components/registry.h"
#include "yarf/texture.h"

namespace yarf {
namespace {

constexpr int kSize = 512;
constexpr size_t kBatch = 4096;

template <typename F>
double Seconds(F&& run) {
  const auto start = std::chrono::steady_clock::now();
  run();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A float RGB image of smooth colours, written as a tiled MIP-mapped EXR.
std::filesystem::path WriteImage(const std::filesystem::path& folder) {
  OIIO::ImageBuf image(OIIO::ImageSpec(kSize, kSize, 3, OIIO::TypeDesc::FLOAT));
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const float texel[3] = {float(x) / kSize, float(y) / kSize, float((x ^ y) & 63) / 63};
      image.setpixel(x, y, texel);
    }
  const std::filesystem::path file = folder / "bench.exr";
  OIIO::ImageSpec config;
  config.attribute("maketx:filtername", "box");
  if (!OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, image, file.string(), config))
    throw Error("could not write " + file.string() + ": " + OIIO::geterror());
  return file;
}

int Main(int argc, char** argv) {
  const size_t n = argc > 1 ? std::stoull(argv[1]) : size_t(1) << 21;
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "yarf-texture-bench";
  std::filesystem::create_directories(folder);
  const std::filesystem::path file = WriteImage(folder);

  // The same lookups for both: random uv, footprints of 1 to 16 texels.
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> unit(0, 1);
  std::vector<float> uv(2 * n), footprint(4 * n);
  for (size_t k = 0; k < n; ++k) {
    uv[2 * k] = unit(rng), uv[2 * k + 1] = unit(rng);
    const float width = (1 + 15 * unit(rng)) / kSize;
    footprint[4 * k] = width, footprint[4 * k + 1] = 0, footprint[4 * k + 2] = 0, footprint[4 * k + 3] = width;
  }

  Registry registry;
  registry.LoadDirectory(YARF_PLUGIN_DIR);
  std::unique_ptr<OIIO::TextureSystem, void (*)(OIIO::TextureSystem*)> system(
      OIIO::TextureSystem::create(false), [](OIIO::TextureSystem* ts) { OIIO::TextureSystem::destroy(ts); });
  system->attribute("max_memory_MB", 64.0f);
  OIIO::TextureSystem::TextureHandle* handle = system->get_texture_handle(OIIO::ustring(file.string()));
  OIIO::TextureSystem::Perthread* thread = system->get_perthread_info();

  // Lookups per second through bitmap with `filter` and through OIIO with
  // `mipmode`, alternating, best of three each: both caches warm, the
  // machine's noise shared.
  const auto compare = [&](const std::string& filter, OIIO::TextureOpt::MipMode mipmode) {
    Properties props;
    props.Set("filename", file);
    props.Set("filter_type", filter);
    props.Set("raw", true);
    const auto bitmap = registry.CreateAs<Texture>("bitmap", props);
    std::vector<float> values(3 * kBatch);
    double through_yarf_sum = 0;
    const auto run_yarf = [&] {
      for (size_t first = 0; first < n; first += kBatch) {
        const size_t m = std::min(kBatch, n - first);
        bitmap->Evaluate({std::span(uv).subspan(2 * first, 2 * m), std::span(footprint).subspan(4 * first, 4 * m)},
                         std::span(values).first(3 * m));
        through_yarf_sum += values[0];
      }
    };
    OIIO::TextureOpt opt;
    opt.interpmode = OIIO::TextureOpt::InterpBilinear;
    opt.mipmode = mipmode;
    opt.swrap = opt.twrap = OIIO::TextureOpt::WrapPeriodic;  // bitmap's default, not the file's
    double direct_sum = 0;
    const auto run_direct = [&] {
      float texel[3];
      for (size_t k = 0; k < n; ++k) {
        OIIO::TextureOpt lookup = opt;  // texture() may change its options
        system->texture(handle, thread, lookup, uv[2 * k], uv[2 * k + 1], footprint[4 * k], footprint[4 * k + 1],
                        footprint[4 * k + 2], footprint[4 * k + 3], 3, texel);
        if (k % kBatch == 0) direct_sum += texel[0];
      }
    };
    double through_yarf = 1e30, direct = 1e30;
    for (int round = 0; round < 3; ++round) {
      through_yarf = std::min(through_yarf, Seconds(run_yarf));
      direct = std::min(direct, Seconds(run_direct));
    }
    std::ostringstream out;
    out << "{\"bitmap_per_second\": " << n / through_yarf << ", \"oiio_direct_per_second\": " << n / direct
        << ", \"bitmap_vs_oiio\": " << direct / through_yarf << ", \"checksums\": [" << through_yarf_sum << ", "
        << direct_sum << "]}";
    return out.str();
  };
  const std::string trilinear = compare("trilinear", OIIO::TextureOpt::MipModeTrilinear);
  const std::string bilinear = compare("bilinear", OIIO::TextureOpt::MipModeNoMIP);
  std::filesystem::remove_all(folder);
  std::cout << "{\"lookups\": " << n << ", \"trilinear\": " << trilinear << ", \"bilinear\": " << bilinear << "}\n";
  return 0;
}

}  // namespace
}  // namespace yarf

int main(int argc, char** argv) {
  try {
    return yarf::Main(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "texture_lookups: " << e.what() << "\n";
    return 1;
  }
}
