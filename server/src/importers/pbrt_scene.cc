// pbrt-v4 scenes: the entry point, the directive loop, transforms and the
// graphics state.
#include <algorithm>
#include <bit>

#include "importers/numbers.h"
#include "importers/pbrt_importer.h"
#include "importers/properties_util.h"

namespace yarf::importers {

namespace fs = std::filesystem;

namespace {

constexpr int kMaxIncludeDepth = 32;
// Files included in all (a file may be included many times, not in a cycle).
constexpr int kMaxIncludes = 10000;
constexpr size_t kMaxAttributeDepth = 10000;
// Values of the Attribute parameters in force at once: pbrt's directives
// have a few dozen parameters each, and every directive of a kind reads
// through them.
constexpr size_t kMaxAttributeDefaultValues = 4096;

}  // namespace

ImportResult ImportPbrt(std::string_view text, const fs::path& file, const ImportOptions& options) {
  const SceneFolder folder(file, options.confine_to_folder);
  Diagnostics diagnostics;
  if (!options.parameters.empty())
    Fail({folder.Display(file), 0}, "pbrt scenes take no parameters (-D is for Mitsuba scenes)");
  PbrtImporter importer(folder, diagnostics, {folder.Display(file), 0});
  importer.ParseFile(text, file, 0);
  return importer.Finish();
}

void PbrtImporter::ParseFile(std::string_view text, const fs::path& file, int depth) {
  std::error_code error;
  files_.push_back(fs::weakly_canonical(fs::absolute(file), error));
  PbrtTokenizer tokens(text, folder_.Display(file));
  while (std::optional<PbrtToken> token = tokens.Next()) {
    if (token->kind != PbrtToken::kWord)
      Fail(token->where, "expected a directive, got " +
                             (token->kind == PbrtToken::kString ? "\"" + token->text + "\"" : token->text));
    Directive(*token, tokens, file, depth);
  }
  files_.pop_back();
}

double PbrtImporter::Number(PbrtTokenizer& tokens, const SourceLocation& where) {
  const std::optional<PbrtToken> token = tokens.Next();
  if (!token) Fail(where, "the file ends where a number was expected");
  const auto value = token->kind == PbrtToken::kWord ? ParseDouble(token->text) : std::nullopt;
  if (!value) Fail(token->where, "expected a number, got '" + token->text + "'");
  return *value;
}

std::string PbrtImporter::Quoted(PbrtTokenizer& tokens, const SourceLocation& where) {
  const std::optional<PbrtToken> token = tokens.Next();
  if (!token) Fail(where, "the file ends where a quoted string was expected");
  if (token->kind != PbrtToken::kString) Fail(token->where, "expected a quoted string, got '" + token->text + "'");
  return token->text;
}

// 16 numbers, bracketed or not, listing the matrix column by column (pbrt
// writes the transpose of the matrix acting on column vectors).
Matrix4 PbrtImporter::Matrix(PbrtTokenizer& tokens, const SourceLocation& where) {
  const bool bracketed = tokens.Peek() && tokens.Peek()->kind == PbrtToken::kOpen;
  if (bracketed) tokens.Next();
  std::array<double, 16> m{};
  for (int i = 0; i < 16; ++i) m[4 * (i % 4) + i / 4] = Number(tokens, where);
  if (bracketed) {
    const std::optional<PbrtToken> close = tokens.Next();
    if (!close || close->kind != PbrtToken::kClose) Fail(where, "expected ']' after 16 numbers");
  }
  return Matrix4(m);
}

PbrtParams PbrtImporter::ParamsOf(PbrtTokenizer& tokens, const std::string& kind) const {
  PbrtParams params = PbrtParams::Parse(tokens);
  // The latest first: the first of a name is the one kept.
  for (const AttributeDefault* d = state_.attribute_defaults.get(); d; d = d->earlier.get())
    if (d->target == kind) params.AddDefault(d->param);
  return params;
}

void PbrtImporter::Directive(const PbrtToken& word, PbrtTokenizer& tokens, const fs::path& file, int depth) {
  const std::string& name = word.text;
  const SourceLocation& where = word.where;
  auto vec3 = [&] {
    const double x = Number(tokens, where), y = Number(tokens, where);
    return Vec3d{x, y, Number(tokens, where)};
  };
  // A directive of a type and parameters (with the Attribute defaults of
  // `kind`, if any).
  auto typed = [&](auto handler, const std::string& kind = "") {
    const std::string type = Quoted(tokens, where);
    PbrtParams params = ParamsOf(tokens, kind);
    (this->*handler)(type, params, where);
  };
  auto before_world = [&](bool expected) {
    if (world_ != expected)
      Fail(where, name + (expected ? " belongs after WorldBegin" : " belongs before WorldBegin"));
  };

  // Transforms set only the shutter-close CTM while ActiveTransform is
  // EndTime: yarf keeps the shutter-open one.
  auto apply = [&](const Matrix4& m, bool replace) {
    if (start_transform_active_) state_.ctm = replace ? m : state_.ctm * m;
  };
  if (name == "Identity") {
    apply(Matrix4(), true);
  } else if (name == "Translate") {
    apply(Matrix4::Translate(vec3()), false);
  } else if (name == "Scale") {
    apply(Matrix4::Scale(vec3()), false);
  } else if (name == "Rotate") {
    const double angle = Number(tokens, where);
    const auto rotation = Matrix4::Rotate(vec3(), angle);
    if (!rotation) Fail(where, "Rotate needs a nonzero axis");
    apply(*rotation, false);
  } else if (name == "LookAt") {
    const Vec3d eye = vec3(), look = vec3(), up = vec3();
    const auto frame = Matrix4::LookAt(eye, look, up);
    const auto camera_from_world = frame ? frame->Inverse() : std::nullopt;
    if (!camera_from_world) Fail(where, "LookAt: eye equals look, or up is parallel to the view");
    apply(*camera_from_world, false);
  } else if (name == "Transform") {
    apply(Matrix(tokens, where), true);
  } else if (name == "ConcatTransform") {
    apply(Matrix(tokens, where), false);
  } else if (name == "CoordinateSystem") {
    coordinate_systems_[Quoted(tokens, where)] = state_.ctm;
  } else if (name == "CoordSysTransform") {
    const std::string system = Quoted(tokens, where);
    const auto it = coordinate_systems_.find(system);
    if (it == coordinate_systems_.end())
      Warn(where, "coordsys:" + system, "unknown coordinate system '" + system + "': CoordSysTransform ignored");
    else
      apply(it->second, true);
  } else if (name == "TransformTimes") {
    Number(tokens, where), Number(tokens, where);
  } else if (name == "ActiveTransform") {
    const std::optional<PbrtToken> which = tokens.Next();
    if (!which || which->kind != PbrtToken::kWord ||
        (which->text != "All" && which->text != "StartTime" && which->text != "EndTime"))
      Fail(where, "ActiveTransform needs All, StartTime or EndTime");
    start_transform_active_ = which->text != "EndTime";
    if (which->text != "All")
      Warn(where, "ActiveTransform", "animated transforms are not supported: shapes stay where the shutter opens");
  } else if (name == "ReverseOrientation") {
    state_.reverse_orientation = !state_.reverse_orientation;
  } else if (name == "TransformBegin" || name == "TransformEnd") {
    if (name == "TransformBegin") {
      if (transforms_.size() >= kMaxAttributeDepth) Fail(where, "TransformBegin nested too deeply");
      transforms_.push_back(state_.ctm);
    } else {
      if (transforms_.empty()) Fail(where, "TransformEnd without TransformBegin");
      state_.ctm = transforms_.back();
      transforms_.pop_back();
    }
  } else if (name == "AttributeBegin") {
    if (attributes_.size() >= kMaxAttributeDepth) Fail(where, "AttributeBegin nested too deeply");
    attributes_.push_back(state_);
  } else if (name == "AttributeEnd") {
    if (attributes_.empty()) Fail(where, "AttributeEnd without AttributeBegin");
    state_ = attributes_.back();
    attributes_.pop_back();
  } else if (name == "Attribute") {
    const std::string target = Quoted(tokens, where);
    if (target != "shape" && target != "light" && target != "material" && target != "medium" && target != "texture")
      Fail(where, "Attribute \"" + target + "\": the target must be shape, light, material, medium or texture");
    // Later defaults of the same name win over earlier ones (ParamsOf).
    const PbrtParams given = PbrtParams::Parse(tokens);
    for (const PbrtParam& p : given.All()) {
      state_.attribute_default_values += std::max<size_t>(1, p.numbers.size() + p.strings.size() + p.bools.size());
      if (state_.attribute_default_values > kMaxAttributeDefaultValues)
        Fail(where, "Attribute parameters in force hold more than " + std::to_string(kMaxAttributeDefaultValues) +
                        " values");
      state_.attribute_defaults =
          std::make_shared<const AttributeDefault>(AttributeDefault{target, p, state_.attribute_defaults});
    }
  } else if (name == "WorldBegin") {
    before_world(false);
    world_ = true;
    state_.ctm = Matrix4();
    coordinate_systems_["world"] = Matrix4();
  } else if (name == "WorldEnd") {
    // pbrt-v3's closing directive: nothing to do.
  } else if (name == "Camera") {
    before_world(false);
    typed(&PbrtImporter::Camera);
  } else if (name == "Film") {
    before_world(false);
    typed(&PbrtImporter::Film);
  } else if (name == "Sampler") {
    before_world(false);
    typed(&PbrtImporter::Sampler);
  } else if (name == "PixelFilter") {
    before_world(false);
    typed(&PbrtImporter::PixelFilter);
  } else if (name == "Integrator" || name == "SurfaceIntegrator") {
    before_world(false);
    typed(&PbrtImporter::Integrator);
  } else if (name == "Option") {
    // "type name" and one value, bracketed or not: renderer settings.
    const std::string option = Quoted(tokens, where);
    const std::optional<PbrtToken> value = tokens.Next();
    if (!value) Fail(where, "Option needs a value");
    if (value->kind == PbrtToken::kOpen)
      for (std::optional<PbrtToken> t = tokens.Next(); !t || t->kind != PbrtToken::kClose; t = tokens.Next())
        if (!t) Fail(where, "unclosed '[' in Option");
    Warn(where, "Option:" + option, "Option \"" + option + "\" ignored");
  } else if (name == "Accelerator") {
    const std::string type = Quoted(tokens, where);
    PbrtParams params = PbrtParams::Parse(tokens);
    Accelerator(type, params, where);
  } else if (name == "ColorSpace") {
    Quoted(tokens, where);
    PbrtParams params = PbrtParams::Parse(tokens);
    Warn(where, name, "ColorSpace is not supported: ignored (colours are read as sRGB)");
  } else if (name == "MakeNamedMedium") {
    const std::string medium = Quoted(tokens, where);
    PbrtParams params = ParamsOf(tokens, "medium");
    MakeNamedMedium(medium, params, where);
  } else if (name == "MediumInterface") {
    // "inside" "outside", or one name for both; an attribute, as the material.
    state_.inside_medium = Quoted(tokens, where);
    state_.outside_medium = state_.inside_medium;
    if (tokens.Peek() && tokens.Peek()->kind == PbrtToken::kString) state_.outside_medium = Quoted(tokens, where);
    state_.medium_where = where;
  } else if (name == "Material") {
    before_world(true);
    const std::string type = Quoted(tokens, where);
    PbrtParams params = ParamsOf(tokens, "material");
    state_.material = MakeMaterial(type, params, where, "");
  } else if (name == "MakeNamedMaterial") {
    before_world(true);
    const std::string material = Quoted(tokens, where);
    PbrtParams params = ParamsOf(tokens, "material");
    const std::string type = params.String("type", "");
    if (type.empty()) Fail(where, "MakeNamedMaterial \"" + material + "\" needs a \"string type\"");
    if (named_materials_.count(material)) Fail(where, "named material '" + material + "' defined twice");
    named_materials_[material] = MakeMaterial(type, params, where, material);
  } else if (name == "NamedMaterial") {
    const std::string material = Quoted(tokens, where);
    const auto it = named_materials_.find(material);
    if (it == named_materials_.end()) Fail(where, "named material '" + material + "' is not defined");
    state_.material = it->second;
  } else if (name == "Texture") {
    before_world(true);
    const std::string texture = Quoted(tokens, where), type = Quoted(tokens, where),
                      texture_class = Quoted(tokens, where);
    PbrtParams params = ParamsOf(tokens, "texture");
    Texture(texture, type, texture_class, params, where);
  } else if (name == "Shape") {
    before_world(true);
    typed(&PbrtImporter::Shape, "shape");
  } else if (name == "LightSource") {
    before_world(true);
    typed(&PbrtImporter::LightSource, "light");
  } else if (name == "AreaLightSource") {
    before_world(true);
    typed(&PbrtImporter::AreaLightSource, "light");
  } else if (name == "ObjectBegin") {
    before_world(true);
    const std::string object = Quoted(tokens, where);
    if (!object_.empty()) Fail(where, "ObjectBegin inside ObjectBegin \"" + object_ + "\"");
    if (assembly_.HasGroup(object)) Fail(where, "object '" + object + "' defined twice");
    attributes_.push_back(state_);
    assembly_.Group(object);
    object_ = object;
    object_where_ = where;
  } else if (name == "ObjectEnd") {
    if (object_.empty()) Fail(where, "ObjectEnd without ObjectBegin");
    if (attributes_.empty()) Fail(where, "ObjectEnd does not match its ObjectBegin's attributes");
    state_ = attributes_.back();
    attributes_.pop_back();
    object_.clear();
  } else if (name == "ObjectInstance") {
    before_world(true);
    const std::string object = Quoted(tokens, where);
    if (!object_.empty()) Fail(where, "ObjectInstance inside an object definition");
    if (!assembly_.HasGroup(object)) Fail(where, "ObjectInstance of undefined object '" + object + "'");
    assembly_.AddInstance(object, state_.ctm, where);
  } else if (name == "Include" || name == "Import") {
    const std::string included = Quoted(tokens, where);
    if (depth >= kMaxIncludeDepth) Fail(where, "includes nested deeper than " + std::to_string(kMaxIncludeDepth));
    if (++includes_ > kMaxIncludes) Fail(where, "more than " + std::to_string(kMaxIncludes) + " includes");
    const fs::path target = folder_.Resolve(included, file, where);
    if (std::find(files_.begin(), files_.end(), target) != files_.end())
      Fail(where, "include cycle: '" + included + "' includes itself");
    const std::string text = ReadTextFile(target, where);
    ParseFile(text, target, depth + 1);
  } else {
    Fail(where, "unknown directive '" + name + "'");
  }
}

ImportResult PbrtImporter::Finish() {
  if (!object_.empty()) Fail(object_where_, "ObjectBegin \"" + object_ + "\" is never ended");
  if (!has_camera_) {
    // pbrt's default camera sits at the origin looking down +z, in vacuum.
    PbrtParams none;
    state_.ctm = Matrix4();
    state_.outside_medium.clear();
    Camera("perspective", none, origin_);
  }
  if (!has_film_) {
    PbrtParams none;
    Film("rgb", none, origin_);
  }
  if (!has_sampler_) {
    PbrtParams none;
    Sampler("zsobol", none, origin_);
  }
  if (!has_filter_) {
    PbrtParams none;
    PixelFilter("gaussian", none, origin_);
  }
  if (!has_integrator_) {
    PbrtParams none;
    Integrator("volpath", none, origin_);
  }
  if (const double exposure = shutter_time_ * iso_ / 100; exposure != 1)
    assembly_.scene().mutable_film()->set_exposure(exposure);
  ResolveMedia();
  ChooseVolumetricTransport();
  // yarf's zsobol indexes the film's points with 32 bits: Morton-ordered
  // pixels of a square of side 2^k, times the samples per pixel rounded up
  // to an even power of two. Past that the padded sequences serve.
  const v1::Film& film = assembly_.scene().film();
  const uint32_t side_bits = std::bit_width(std::max({film.width(), film.height(), 1u}) - 1);
  const uint32_t sample_bits = std::bit_width(std::max(sample_count_, 1u) - 1);
  if (assembly_.scene().sampler().class_name() == "zsobol" && 2 * side_bits + sample_bits + sample_bits % 2 > 32) {
    Warn(origin_, "sampler:zsobol-size",
         "zsobol: this film and sample count need more than 2^32 points: padded Sobol used");
    *assembly_.scene().mutable_sampler() = Spec("sobol");
  }
  ImportResult result;
  result.scene = assembly_.Finish();
  result.sample_count = sample_count_;
  result.crop = crop_;
  result.warnings = diagnostics_.Lines();
  return result;
}

}  // namespace yarf::importers
