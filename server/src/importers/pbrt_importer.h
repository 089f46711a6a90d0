// The pbrt-v4 importer's state, shared by the files that map each kind of
// directive (pbrt_scene.cc, pbrt_camera.cc, pbrt_materials.cc,
// pbrt_textures.cc, pbrt_spectra.cc, pbrt_shapes.cc, pbrt_lights.cc,
// pbrt_media.cc).
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "importers/diagnostics.h"
#include "importers/import.h"
#include "importers/mesh_shapes.h"
#include "importers/pbrt_params.h"
#include "importers/pbrt_tokenizer.h"
#include "importers/properties_util.h"
#include "importers/scene_assembly.h"
#include "importers/scene_folder.h"
#include "importers/spectrum.h"

namespace yarf::importers {

class PbrtImporter {
 public:
  // `origin` names the scene file, for what has no line of its own.
  PbrtImporter(const SceneFolder& folder, Diagnostics& diagnostics, SourceLocation origin)
      : folder_(folder), diagnostics_(diagnostics), origin_(std::move(origin)) {}

  // Reads one file's directives (Include and Import recurse).
  void ParseFile(std::string_view text, const std::filesystem::path& file, int include_depth);
  ImportResult Finish();

 private:
  struct AreaLight {
    Rgb radiance;  // L × scale, before `power`; with an image, the image's factor
    bool two_sided = false;
    double power = -1;  // pbrt-v4's `power` in W; ≤ 0 when not given
    SourceLocation where, power_where;
    std::filesystem::path image;  // pbrt's `filename`: radiance from an image
  };
  // One parameter default of an Attribute directive, before those given
  // earlier.
  struct AttributeDefault {
    std::string target;
    PbrtParam param;
    std::shared_ptr<const AttributeDefault> earlier;
  };
  // What AttributeBegin saves and AttributeEnd restores.
  struct State {
    Matrix4 ctm;
    bool reverse_orientation = false;
    std::string material;  // yarf material; "" is the default, kInterface none
    std::optional<AreaLight> area_light;
    // MediumInterface: pbrt's names of the media inside and outside the
    // shapes that follow ("" is vacuum), and where it was given.
    std::string inside_medium, outside_medium;
    SourceLocation medium_where;
    // Attribute "shape" | "light" | "material" | "medium" | "texture":
    // defaults for the parameters of every such directive that follows,
    // the latest first. Shared, not copied, by AttributeBegin.
    std::shared_ptr<const AttributeDefault> attribute_defaults;
    size_t attribute_default_values = 0;  // their numbers, strings and bools
  };
  static constexpr const char* kInterface = "\x01interface";

  // pbrt_scene.cc
  void Directive(const PbrtToken& word, PbrtTokenizer& tokens, const std::filesystem::path& file, int depth);
  double Number(PbrtTokenizer& tokens, const SourceLocation& where);
  std::string Quoted(PbrtTokenizer& tokens, const SourceLocation& where);
  Matrix4 Matrix(PbrtTokenizer& tokens, const SourceLocation& where);
  // A directive's parameters with the Attribute defaults for its kind.
  PbrtParams ParamsOf(PbrtTokenizer& tokens, const std::string& kind) const;
  void Warn(const SourceLocation& where, const std::string& key, const std::string& message) {
    diagnostics_.Warn(where, key, message);
  }

  // pbrt_camera.cc
  void Camera(const std::string& type, PbrtParams& params, const SourceLocation& where);
  void Film(const std::string& type, PbrtParams& params, const SourceLocation& where);
  void Sampler(const std::string& type, PbrtParams& params, const SourceLocation& where);
  void PixelFilter(const std::string& type, PbrtParams& params, const SourceLocation& where);
  void Integrator(const std::string& type, PbrtParams& params, const SourceLocation& where);
  void Accelerator(const std::string& type, PbrtParams& params, const SourceLocation& where);

  // pbrt_materials.cc
  std::string MakeMaterial(const std::string& type, PbrtParams& params, const SourceLocation& where,
                           const std::string& name);
  // pbrt_textures.cc
  void Texture(const std::string& name, const std::string& type, const std::string& texture_class,
               PbrtParams& params, const SourceLocation& where);
  // pbrt_spectra.cc: a spectrum-valued parameter (rgb, spectrum, blackbody, float or a
  // texture) as RGB.
  Rgb Colour(PbrtParams& params, const std::string& name, Rgb fallback, SpectrumUse use, const SourceLocation& where);
  // A float parameter or float texture (its mean).
  double FloatOrTexture(PbrtParams& params, const std::string& name, double fallback);
  // The same where yarf takes textures: a texture reference names the
  // scene texture it became (or, for one yarf has no class for, its mean).
  Textured TexturedColour(PbrtParams& params, const std::string& name, Rgb fallback, SpectrumUse use,
                          const SourceLocation& where);
  Textured TexturedFloat(PbrtParams& params, const std::string& name, double fallback);

  // pbrt_shapes.cc
  void Shape(const std::string& type, PbrtParams& params, const SourceLocation& where);
  // A loopsubdiv shape's refined mesh from its control mesh and levels.
  TriangleArrays Subdivided(const std::vector<double>& p, const std::vector<uint32_t>& indices, PbrtParams& params,
                            const SourceLocation& where);

  // pbrt_media.cc: MakeNamedMedium, and the media shapes and the camera
  // name, resolved once every medium is known (pbrt-v4 resolves them at
  // the end too).
  void MakeNamedMedium(const std::string& name, PbrtParams& params, const SourceLocation& where);
  // The shape bounds the media of the MediumInterface in force, if they
  // differ (pbrt-v4's medium transition); a pbrt name for now.
  void SetMedia(v1::SceneShape& shape);
  // The homogeneous medium inside a subsurface material (pbrt_materials.cc).
  v1::Properties SubsurfaceMedium(PbrtParams& params, const SourceLocation& where);
  void ResolveMedia();
  // Transport: volpath for pbrt's volpath where the scene has media.
  void ChooseVolumetricTransport();

  // pbrt_lights.cc
  void LightSource(const std::string& type, PbrtParams& params, const SourceLocation& where);
  void AreaLightSource(const std::string& type, PbrtParams& params, const SourceLocation& where);
  void DistantLight(PbrtParams& params, const SourceLocation& where);
  void ImageLight(const std::string& type, PbrtParams& params, const SourceLocation& where);
  void InfiniteLight(PbrtParams& params, const SourceLocation& where);
  // The radiance of the area light in force on a shape made of pbrt-v4
  // shapes of these areas (one per triangle of a mesh), `power` applied;
  // no areas where they are not known.
  Rgb AreaLightRadiance(const std::vector<double>& areas, const std::string& shape);

  const SceneFolder& folder_;
  Diagnostics& diagnostics_;
  SourceLocation origin_;
  SceneAssembly assembly_;
  State state_;
  std::vector<State> attributes_;   // AttributeBegin/ObjectBegin saves
  std::vector<Matrix4> transforms_;  // TransformBegin saves
  std::map<std::string, Matrix4> coordinate_systems_;
  std::map<std::string, std::string> named_materials_;  // pbrt name → yarf material
  // pbrt's named media → the yarf medium made ("" for one left out).
  std::map<std::string, std::string> media_;
  // A subsurface material's yarf name → the key in media_ of the medium
  // its shapes enclose.
  std::map<std::string, std::string> subsurface_media_;
  // Each medium a shape or the camera names, and where.
  std::vector<std::pair<std::string, SourceLocation>> medium_uses_;
  std::string integrator_type_;  // pbrt's, for media
  SourceLocation integrator_where_;
  std::map<std::string, std::string> material_cache_;   // content → yarf material
  // pbrt texture name → what it became: a scene texture and its mean.
  std::map<std::string, Textured> spectrum_textures_;
  std::map<std::string, Textured> float_textures_;
  std::vector<std::filesystem::path> files_;  // the files being read, for include cycles
  int includes_ = 0;
  std::string object_;  // the ObjectBegin being defined
  SourceLocation object_where_;
  bool world_ = false;
  bool start_transform_active_ = true;  // ActiveTransform is not EndTime
  bool has_camera_ = false, has_film_ = false, has_sampler_ = false, has_integrator_ = false, has_filter_ = false;
  uint32_t sample_count_ = 16;
  std::string crop_;  // ImportResult::crop
  // pbrt-v4's imaging ratio: the camera's shutter open time × the film's ISO / 100.
  double shutter_time_ = 1, iso_ = 100;
  int nesting_ = 0;
};

}  // namespace yarf::importers
