// bitmap — an image file looked up by uv (Mitsuba's `bitmap`, pbrt-v4's
// `imagemap`), from memory or, MIP-mapped, by OpenImageIO's TextureSystem
//
// Parameters: Bitmap::Parameters() below. Several settings have two
// names, Mitsuba's and pbrt's (filter_type / filter, wrap_mode / wrap,
// raw / encoding): a texture gives one of each pair.
//   Filters: "nearest" (pbrt: "point"), the texel containing the point;
//   "bilinear", between the four nearest texels of the full image, no
//   MIP map (as Mitsuba and pbrt's bilinear); "trilinear", bilinear in
//   the two MIP levels the footprint's width selects, blended; "ewa",
//   OpenImageIO's anisotropic MIP filter along the footprint's major axis.
//   Wraps: "repeat", "mirror" (Mitsuba), "clamp", "black" (pbrt); pbrt's
//   "octahedralsphere" (of its equal-area environment maps) is refused.
//   Encoding of integer (8- or 16-bit) images: raw = false or "sRGB"
//   decode the sRGB curve, raw = true or "linear" take the stored values,
//   "gamma G" (pbrt) gives value^G. Decoding comes before filtering;
//   float images are linear and never decoded.
//   The uv map before lookup (uv_map.h) is applied to yarf's uv (v = 0
//   at the image's top row). The value is scale · texel, then
//   max(0, 1 − that) if inverted (pbrt's order).
//
// Channels: 1 for a grey image (with or without alpha), else 3 (the first
// three; alpha is ignored). Mean: the mean over the texels of the value
// above (it ignores the uv map and the wrap mode).
//
// The image is decoded here to linear float. Without a MIP map (nearest,
// bilinear) it is looked up in memory (texel_grid.h). With one
// (trilinear, ewa), OpenImageIO 2.4's TextureSystem filters it: it has no
// colour conversion of its own, so the decoded image is written as a
// tiled, MIP-mapped float EXR into a private temporary folder this
// instance owns, and the TextureSystem reads that, each instance its own
// with a bounded 64 MiB cache: no state is shared between instances, and
// lookups are thread-safe.
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/texture.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "linear_image.h"
#include "temporary_folder.h"
#include "texel_grid.h"
#include "texture_rows.h"
#include "uv_map.h"
#include "yarf/plugin.h"

namespace {

using yarf::Error;
using yarf::Properties;
using yarf::textures::Encoding;
using yarf::textures::LinearImage;
using yarf::textures::Wrap;

// The Mitsuba key's value, or else the pbrt key's; both at once is an error.
std::string ReadEither(const Properties& props, const std::string& mitsuba, const std::string& pbrt,
                       const std::string& fallback) {
  if (props.Has(mitsuba) && props.Has(pbrt))
    throw Error("properties '" + mitsuba + "' and '" + pbrt + "' are two names of one setting: give one");
  return props.Has(pbrt) ? props.String(pbrt, fallback) : props.String(mitsuba, fallback);
}

std::string KeyOf(const Properties& props, const std::string& mitsuba, const std::string& pbrt) {
  return props.Has(pbrt) ? pbrt : mitsuba;
}

// How a bitmap is looked up: its filter, its wrap and, for ewa, the bound
// on the footprint's axis ratio.
struct Lookup {
  enum class Filter { kNearest, kBilinear, kTrilinear, kEwa };
  Filter filter = Filter::kBilinear;
  Wrap wrap = Wrap::kRepeat;
  int max_anisotropy = 8;

  bool MipMapped() const { return filter == Filter::kTrilinear || filter == Filter::kEwa; }
};

Lookup ReadLookup(const Properties& props) {
  Lookup lookup;
  const std::string filter = ReadEither(props, "filter_type", "filter", "bilinear");
  if (filter == "nearest" || filter == "point") {
    lookup.filter = Lookup::Filter::kNearest;
  } else if (filter == "bilinear") {
    lookup.filter = Lookup::Filter::kBilinear;
  } else if (filter == "trilinear") {
    lookup.filter = Lookup::Filter::kTrilinear;
  } else if (filter == "ewa") {
    lookup.filter = Lookup::Filter::kEwa;
  } else {
    throw Error("property '" + KeyOf(props, "filter_type", "filter") + "' must be one of nearest (or point), " +
                "bilinear, trilinear, ewa; got '" + filter + "'");
  }

  const std::string wrap = ReadEither(props, "wrap_mode", "wrap", "repeat");
  const std::string wrap_key = KeyOf(props, "wrap_mode", "wrap");
  if (wrap == "repeat") {
    lookup.wrap = Wrap::kRepeat;
  } else if (wrap == "mirror") {
    lookup.wrap = Wrap::kMirror;
  } else if (wrap == "clamp") {
    lookup.wrap = Wrap::kClamp;
  } else if (wrap == "black") {
    lookup.wrap = Wrap::kBlack;
  } else if (wrap == "octahedralsphere") {
    throw Error("property '" + wrap_key + "': the octahedral sphere wrap (of pbrt's equal-area environment " +
                "maps) is not supported for textures");
  } else {
    throw Error("property '" + wrap_key + "' must be one of repeat, mirror, clamp, black; got '" + wrap + "'");
  }

  const double anisotropy = props.Float("maxanisotropy", 8.0);
  if (!(anisotropy >= 1.0 && anisotropy <= 1024.0))
    throw Error("property 'maxanisotropy' must lie in [1, 1024]");
  lookup.max_anisotropy = int(std::lround(anisotropy));
  return lookup;
}

// The TextureSystem's options for a MIP-mapped lookup.
OIIO::TextureOpt MipOptions(const Lookup& lookup) {
  OIIO::TextureOpt opt;
  opt.interpmode = OIIO::TextureOpt::InterpBilinear;
  opt.mipmode =
      lookup.filter == Lookup::Filter::kEwa ? OIIO::TextureOpt::MipModeAniso : OIIO::TextureOpt::MipModeTrilinear;
  const auto wrap = [&] {
    switch (lookup.wrap) {
      case Wrap::kMirror:
        return OIIO::TextureOpt::WrapMirror;
      case Wrap::kClamp:
        return OIIO::TextureOpt::WrapClamp;
      case Wrap::kBlack:
        return OIIO::TextureOpt::WrapBlack;
      case Wrap::kRepeat:
        break;
    }
    return OIIO::TextureOpt::WrapPeriodic;
  }();
  opt.swrap = opt.twrap = wrap;
  opt.anisotropic = lookup.max_anisotropy;
  return opt;
}

Encoding ReadEncoding(const Properties& props) {
  Encoding encoding;
  if (props.Has("raw") && props.Has("encoding"))
    throw Error("properties 'raw' (Mitsuba) and 'encoding' (pbrt) both set how texels are decoded: give one");
  if (props.Has("raw")) {
    encoding.kind = props.Bool("raw", false) ? Encoding::Kind::kLinear : Encoding::Kind::kSrgb;
    return encoding;
  }
  const std::string name = props.String("encoding", "sRGB");
  if (name == "sRGB") return encoding;
  if (name == "linear") {
    encoding.kind = Encoding::Kind::kLinear;
    return encoding;
  }
  if (name.rfind("gamma ", 0) == 0) {
    size_t used = 0;
    double gamma = 0;
    try {
      gamma = std::stod(name.substr(6), &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == name.size() - 6 && gamma > 0 && gamma <= 100) {
      encoding.kind = Encoding::Kind::kGamma;
      encoding.gamma = gamma;
      return encoding;
    }
  }
  throw Error("property 'encoding' must be sRGB, linear or \"gamma G\" with 0 < G <= 100; got '" + name + "'");
}

// Writes `image` as a tiled float texture with all its MIP levels, each
// level the box average of the one above.
void WriteMipmapped(LinearImage& image, const std::filesystem::path& file) {
  const OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeFloat);
  const OIIO::ImageBuf source(spec, image.texels.data());  // wraps the texels, no copy
  OIIO::ImageSpec config;
  config.format = OIIO::TypeFloat;
  config.tile_width = config.tile_height = 64;
  config.attribute("maketx:filtername", "box");
  config.attribute("maketx:hash", 0);  // the file's SHA-1: not needed for a private file
  std::ostringstream log;
  if (!OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, source, file.string(), config, &log))
    throw Error("property 'filename': the MIP-mapped copy of the image could not be written: " + log.str());
}

struct TextureSystemDeleter {
  void operator()(OIIO::TextureSystem* system) const { OIIO::TextureSystem::destroy(system); }
};

// An image MIP-mapped into a private file, filtered by its own
// TextureSystem over a footprint.
class MipMappedImage {
 public:
  MipMappedImage(LinearImage& image, const Lookup& lookup, const std::filesystem::path& source)
      : options_(MipOptions(lookup)), source_(source), folder_("yarf-bitmap") {
    const std::filesystem::path texture_file = folder_.path() / "texture.exr";
    WriteMipmapped(image, texture_file);
    system_.reset(OIIO::TextureSystem::create(false));
    if (!system_) throw Error("the image texture system could not be created");
    system_->attribute("max_memory_MB", 64.0f);
    system_->attribute("max_open_files", 4);
    system_->attribute("deduplicate", 0);
    handle_ = system_->get_texture_handle(OIIO::ustring(texture_file.string()));
    if (!handle_ || !system_->good(handle_))
      throw Error("property 'filename': the MIP-mapped copy of the image could not be opened: " +
                  system_->geterror());
  }

  // `channels` values at (s, t) over the footprint d = (ds/dx, dt/dx, ds/dy, dt/dy).
  void At(OIIO::TextureSystem::Perthread* thread, double s, double t, const std::array<double, 4>& d, int channels,
          float* out) const {
    OIIO::TextureOpt opt = options_;  // texture() may change its options
    if (!system_->texture(handle_, thread, opt, float(s), float(t), float(d[0]), float(d[1]), float(d[2]),
                          float(d[3]), channels, out))
      throw Error("bitmap '" + source_.filename().string() + "': lookup failed: " + system_->geterror());
  }

  OIIO::TextureSystem::Perthread* ThisThread() const { return system_->get_perthread_info(); }

 private:
  OIIO::TextureOpt options_;
  std::filesystem::path source_;
  // Declared before the texture system, so destroyed after it: the
  // system's open file lives in this folder.
  yarf::textures::TemporaryFolder folder_;
  std::unique_ptr<OIIO::TextureSystem, TextureSystemDeleter> system_;
  OIIO::TextureSystem::TextureHandle* handle_ = nullptr;  // owned by system_
};

class Bitmap final : public yarf::Texture {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    const std::vector<std::string> filters = {"nearest", "point", "bilinear", "trilinear", "ewa"};
    const std::vector<std::string> wraps = {"repeat", "mirror", "clamp", "black"};
    yarf::ParameterSchema schema = yarf::textures::ImageFileParameters("the image; it or asset is required");
    schema.insert(schema.end(), {
        P::String("filter_type").Choices(filters).Doc("the lookup's filter (Mitsuba's name); bilinear when absent"),
        P::String("filter").Choices(filters).Doc("the same, pbrt's name"),
        P::String("wrap_mode").Choices(wraps).Doc("outside [0, 1]² (Mitsuba's name); repeat when absent"),
        P::String("wrap").Choices(wraps).Doc("the same, pbrt's name"),
        P::Bool("raw").Doc("takes an integer image's values as they are (Mitsuba); false when absent"),
        P::String("encoding").Doc("integer images' encoding: sRGB (when absent), linear or \"gamma G\" (pbrt)"),
        P::Float("scale").Default(1).Doc("multiplies the texels"),
        P::Bool("invert").Default(false).Doc("gives max(0, 1 − value) (pbrt)"),
        P::Float("maxanisotropy").Default(8).Range(1, 1024).Doc("bound on the ewa filter's axis ratio (pbrt)"),
    });
    const yarf::ParameterSchema map = yarf::textures::UvMapParameters();
    schema.insert(schema.end(), map.begin(), map.end());
    return schema;
  }

  explicit Bitmap(const Properties& props)
      : lookup_(ReadLookup(props)),
        map_(yarf::textures::ReadUvMap(props)),
        scale_(float(yarf::textures::RequireFinite(props.Float("scale", 1.0), "scale"))),
        invert_(props.Bool("invert", false)) {
    const std::filesystem::path file = props.ResolvedFile("filename");
    LinearImage image = yarf::textures::ReadLinearImage(file, ReadEncoding(props), "filename");
    channels_ = uint32_t(image.channels);
    mean_ = MeanOf(image);
    if (lookup_.MipMapped())
      mipmapped_ = std::make_unique<MipMappedImage>(image, lookup_, file);
    else
      grid_ = std::make_unique<yarf::textures::TexelGrid>(std::move(image), lookup_.wrap);
  }

  uint32_t Channels() const override { return channels_; }

  void Evaluate(const yarf::SurfacePoints& at, std::span<float> value) const override {
    yarf::textures::CheckShapes(at, value, channels_);
    OIIO::TextureSystem::Perthread* thread = mipmapped_ ? mipmapped_->ThisThread() : nullptr;
    float texel[3];
    for (size_t k = 0; k < at.Count(); ++k) {
      const double u = at.uv[2 * k], v = at.uv[2 * k + 1];
      // OIIO's (s, t) are yarf's (u, v): t = 0 at the top row.
      const double s = map_.U(u, v), t = map_.V(u, v);
      if (mipmapped_)
        mipmapped_->At(thread, s, t, map_.Footprint(yarf::textures::FootprintAt(at, k)), int(channels_), texel);
      else if (lookup_.filter == Lookup::Filter::kNearest)
        grid_->Nearest(s, t, texel);
      else
        grid_->Bilinear(s, t, texel);
      for (uint32_t c = 0; c < channels_; ++c) value[k * channels_ + c] = Adjust(texel[c]);
    }
  }

  std::vector<float> Mean() const override { return mean_; }
  bool ReadsFootprints() const override { return mipmapped_ != nullptr; }

 private:
  // pbrt's order: scale first, then invert.
  float Adjust(float texel) const {
    const float scaled = scale_ * texel;
    return invert_ ? std::max(0.0f, 1.0f - scaled) : scaled;
  }

  std::vector<float> MeanOf(const LinearImage& image) const {
    std::vector<double> sum(image.channels, 0.0);
    for (size_t i = 0; i < image.texels.size(); ++i) sum[i % image.channels] += Adjust(image.texels[i]);
    const double count = double(image.width) * double(image.height);
    std::vector<float> mean(image.channels);
    for (int c = 0; c < image.channels; ++c) mean[c] = float(sum[c] / count);
    return mean;
  }

  Lookup lookup_;
  yarf::textures::UvMap map_;
  float scale_;
  bool invert_;
  uint32_t channels_ = 0;
  std::vector<float> mean_;
  // One of the two, by the filter.
  std::unique_ptr<yarf::textures::TexelGrid> grid_;
  std::unique_ptr<MipMappedImage> mipmapped_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Bitmap>(registrar, "bitmap", "1.0.0",
                         "An image file looked up by uv, decoded to linear; MIP-mapped filters by OpenImageIO");
}
