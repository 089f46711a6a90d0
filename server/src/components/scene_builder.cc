#include "components/scene_builder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "components/properties_proto.h"
#include "kernel/film.h"
#include "yarf/error.h"

namespace yarf {
namespace {

std::string ShapeName(const v1::SceneShape& shape, size_t index) {
  return "shape " + std::to_string(index) + (shape.name().empty() ? "" : " ('" + shape.name() + "')");
}

std::string LightName(const v1::Light& light, size_t index) {
  return "light " + std::to_string(index) + (light.name().empty() ? "" : " ('" + light.name() + "')");
}

// A placement the kernel can invert in float precision: its linear part
// neither collapses nor blows up space (singular values within
// [1e-12, 1e12], Frobenius condition number at most 1e8), its translation
// is a sane position. Embree inverts instance transforms; a singular one
// gives rays of NaNs.
void CheckPlacement(const Transform& t, const std::string& what) {
  const auto& m = t.m;
  for (int i : {3, 7, 11})
    if (!(std::abs(m[i]) <= 1e12)) throw Error(what + ": translation beyond 1e12 scene units");
  double linear = 0;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) linear += m[row * 4 + col] * m[row * 4 + col];
  // The inverse is the cofactor matrix, transposed, over the determinant.
  double cofactors = 0;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) {
      const int r0 = (row + 1) % 3, r1 = (row + 2) % 3, c0 = (col + 1) % 3, c1 = (col + 2) % 3;
      const double c = m[r0 * 4 + c0] * m[r1 * 4 + c1] - m[r0 * 4 + c1] * m[r1 * 4 + c0];
      cofactors += c * c;
    }
  const double norm = std::sqrt(linear), det = std::abs(t.Determinant3());
  const double inverse_norm = det > 0 ? std::sqrt(cofactors) / det : INFINITY;
  if (!(norm <= 1e12 && inverse_norm <= 1e12 && norm * inverse_norm <= 1e8))
    throw Error(what + ": degenerate to_world (it collapses or stretches space too far to be inverted; scale "
                "factors must lie within [1e-12, 1e12] and within a ratio of 1e8 of each other)");
}

Transform ShapeTransform(const v1::SceneShape& shape, const std::string& what) {
  return shape.has_to_world() ? FromProto(shape.to_world(), what + " to_world") : Transform{};
}

// Curves as the kernel takes them, in object space (points beyond the
// last whole one dropped: ValidateShapes refuses them first).
CurveGeometry CurvesOf(const v1::Curves& curves) {
  CurveGeometry out;
  switch (curves.basis()) {
    case v1::Curves::BASIS_BSPLINE:
      out.basis = CurveGeometry::Basis::kBSpline;
      break;
    case v1::Curves::BASIS_LINEAR:
      out.basis = CurveGeometry::Basis::kLinear;
      break;
    default:
      out.basis = CurveGeometry::Basis::kBezier;
  }
  out.flat = curves.form() == v1::Curves::FORM_FLAT;
  for (int i = 0; i + 3 < curves.points_size(); i += 4)
    out.points.push_back({curves.points(i), curves.points(i + 1), curves.points(i + 2), curves.points(i + 3)});
  out.segments.assign(curves.segments().begin(), curves.segments().end());
  return out;
}

// An asset reference must name a hash and say how to parse the bytes:
// there is no file name to guess the format from.
void ValidateMeshAsset(const v1::Mesh& mesh, const std::string& what) {
  const std::string& hash = mesh.asset();
  if (!IsSha256(hash))
    throw Error(what + ": mesh asset '" + hash.substr(0, 80) + "' is not a SHA-256 (64 lowercase hex digits)");
  if (mesh.format() != "obj" && mesh.format() != "ply")
    throw Error(what + ": mesh asset " + hash + " needs `format` obj or ply, not '" + mesh.format().substr(0, 20) +
                "'");
}

void RequireShapeAssets(const google::protobuf::RepeatedPtrField<v1::SceneShape>& shapes, const AssetSource& assets,
                        const std::string& where) {
  for (int i = 0; i < shapes.size(); ++i) {
    const v1::SceneShape& s = shapes[i];
    if (s.has_mesh() && s.mesh().has_asset() && !assets.Has(s.mesh().asset()))
      throw Error(where + ShapeName(s, i) + ": mesh asset " + s.mesh().asset() +
                  " is not on this server; upload it with AssetService.Upload before submitting");
  }
}

// The names a scene's shapes may refer to.
struct SceneNames {
  std::set<std::string> materials, textures, media;
};

void ValidateShapes(const google::protobuf::RepeatedPtrField<v1::SceneShape>& shapes, const SceneNames& names,
                    const std::string& where) {
  for (int i = 0; i < shapes.size(); ++i) {
    const v1::SceneShape& s = shapes[i];
    const std::string what = where + ShapeName(s, i);
    if (s.geometry_case() == v1::SceneShape::GEOMETRY_NOT_SET) throw Error(what + " has no geometry");
    if (s.material().empty()) throw Error(what + " has no material");
    if (!names.materials.count(s.material()))
      throw Error(what + " uses unknown material '" + s.material() + "'");
    if (s.has_emitter() && s.emitter().class_name().empty())
      throw Error(what + " has an emitter without a class");
    if (!s.alpha().empty() && !names.textures.count(s.alpha()))
      throw Error(what + ": alpha names '" + s.alpha() + "', which is not a texture of the scene");
    if (!s.alpha().empty() && s.has_sphere()) throw Error(what + ": alpha cut-outs are for meshes, not spheres");
    if (!s.alpha().empty() && s.has_curves()) throw Error(what + ": alpha cut-outs are for meshes, not curves");
    if (s.has_curves() && s.has_emitter()) throw Error(what + " is curves, which cannot emit light");
    if (s.has_curves()) {
      if (!v1::Curves::Basis_IsValid(s.curves().basis()) || !v1::Curves::Form_IsValid(s.curves().form()))
        throw Error(what + ": unknown curve basis or form");
      if (s.curves().points_size() % 4 != 0)
        throw Error(what + ": curves need x, y, z and a radius (4 numbers) per control point");
      if (const std::string defect = CurvesOf(s.curves()).Defect(); !defect.empty()) throw Error(what + ": " + defect);
    }
    for (const std::string* medium : {&s.interior(), &s.exterior()})
      if (!medium->empty() && !names.media.count(*medium))
        throw Error(what + ": medium '" + *medium + "' is not a medium of the scene");
    if (s.has_sphere() && !(s.sphere().radius() > 0 && std::isfinite(s.sphere().radius())))
      throw Error(what + ": sphere radius must be positive");
    if (s.has_to_world()) CheckPlacement(FromProto(s.to_world(), what + " to_world"), what);
    if (s.has_to_world_end()) {
      if (!where.empty()) throw Error(what + ": only shapes placed in the world may move (to_world_end)");
      if (s.has_emitter()) throw Error(what + " moves and emits: moving lights are not supported");
      CheckPlacement(FromProto(s.to_world_end(), what + " to_world_end"), what + " to_world_end");
    }
    if (s.has_mesh() && s.mesh().has_asset()) ValidateMeshAsset(s.mesh(), what);
    if (s.has_mesh() && s.mesh().source_case() == v1::Mesh::SOURCE_NOT_SET) {
      if (s.mesh().positions_size() % 3 != 0 || s.mesh().indices_size() % 3 != 0 ||
          s.mesh().indices_size() == 0)
        throw Error(what + ": inline mesh needs xyz positions and index triples");
      for (uint32_t index : s.mesh().indices())
        if (index >= uint32_t(s.mesh().positions_size() / 3))
          throw Error(what + ": mesh index " + std::to_string(index) + " out of range");
    }
  }
}

// The file `file` (a `kind`, e.g. "mesh file") names under the server's
// asset root, confined to it.
std::filesystem::path ConfinedPath(const std::filesystem::path& root, const std::string& file,
                                   const std::string& kind, const std::string& what) {
  namespace fs = std::filesystem;
  if (root.empty())
    throw Error(what + ": " + kind + " '" + file +
                "' cannot be read: this server has no asset root; upload the file (AssetService) and "
                "name its SHA-256 in `asset`");
  const fs::path base = fs::weakly_canonical(root);
  const fs::path path = fs::weakly_canonical(base / file);
  const auto [end, _] = std::mismatch(base.begin(), base.end(), path.begin(), path.end());
  if (end != base.end()) throw Error(what + ": " + kind + " '" + file + "' lies outside the scene folder");
  std::error_code error;
  if (!fs::is_regular_file(path, error)) throw Error(what + ": " + kind + " '" + file + "' not found");
  return path;
}

std::string TextureName(const v1::SceneTexture& texture) {
  return "texture '" + texture.name() + "' (" + texture.texture().class_name() + ")";
}

std::string MaterialName(const v1::Material& material) {
  return "material '" + material.name() + "' (" + material.class_name() + ")";
}

// Textures and materials refer to those before them, and a lookup of one
// evaluates the whole tree its references make: a chain or a mix of mixes
// of a few dozen parts would make every lookup take forever, or exhaust a
// render thread's stack. Each tree is bounded (SceneLimits::kMaxReferenceTree).
void CheckReferenceTrees(const v1::Scene& scene) {
  // References resolve to a texture first, then to a material (MakeComponent).
  std::map<std::string, uint64_t> texture_tree, material_tree;
  const auto tree_of = [&](const v1::Properties& properties, bool materials, const std::string& what) {
    uint64_t size = 1;
    for (const auto& [key, value] : properties.values()) {
      if (value.value_case() != v1::Property::kReference) continue;
      if (auto t = texture_tree.find(value.reference()); t != texture_tree.end())
        size += t->second;
      else if (auto m = material_tree.find(value.reference()); materials && m != material_tree.end())
        size += m->second;
    }
    if (size > SceneLimits::kMaxReferenceTree)
      throw Error(what + ": its references make a tree of " + std::to_string(size) + " parts (at most " +
                  std::to_string(SceneLimits::kMaxReferenceTree) + ", a part shared by two references counted twice)");
    return size;
  };
  for (const v1::SceneTexture& t : scene.textures())
    texture_tree[t.name()] = tree_of(t.texture().properties(), false, TextureName(t));
  for (const v1::Material& m : scene.materials())
    material_tree[m.name()] = tree_of(m.properties(), true, MaterialName(m));
}

// Whether a component's property names a file of its own: `filename`, or
// `NAME_filename` for components that read several (a medium's grids).
// Such a file is read under the scene's folder; the same key with `asset`
// for `filename` names an uploaded one instead.
bool KeyEndsWith(const std::string& key, std::string_view word) {
  return key == word || (key.size() > word.size() + 1 && key.ends_with(word) && key[key.size() - word.size() - 1] == '_');
}
bool IsFileKey(const std::string& key) { return KeyEndsWith(key, "filename"); }
bool IsAssetKey(const std::string& key) { return KeyEndsWith(key, "asset"); }
std::string FileKeyOfAsset(const std::string& asset_key) {
  return asset_key.substr(0, asset_key.size() - std::string_view("asset").size()) + "filename";
}

// The properties of a component that name uploaded assets.
std::vector<std::pair<std::string, const v1::Property*>> AssetsOf(const v1::ComponentSpec& spec) {
  std::vector<std::pair<std::string, const v1::Property*>> out;
  for (const auto& [key, value] : spec.properties().values())
    if (IsAssetKey(key)) out.emplace_back(key, &value);
  return out;
}

std::string MediumName(const v1::SceneMedium& medium) {
  return "medium '" + medium.name() + "' (" + medium.medium().class_name() + ")";
}

// The components of a scene that may read files of their own (textures'
// images, environment maps, media's grids), each with its name for errors.
std::vector<std::pair<std::string, const v1::ComponentSpec*>> FileComponents(const v1::Scene& scene) {
  std::vector<std::pair<std::string, const v1::ComponentSpec*>> out;
  for (const v1::SceneTexture& t : scene.textures()) out.emplace_back(TextureName(t), &t.texture());
  for (int i = 0; i < scene.lights_size(); ++i) out.emplace_back(LightName(scene.lights(i), i), &scene.lights(i).emitter());
  for (const v1::SceneMedium& m : scene.media()) out.emplace_back(MediumName(m), &m.medium());
  return out;
}

class Builder {
 public:
  Builder(const v1::Scene& scene, const SceneSources& sources) : scene_(scene), sources_(sources) {}
  // scene_references_ points into the builder itself.
  Builder(const Builder&) = delete;
  Builder& operator=(const Builder&) = delete;

  std::unique_ptr<KernelScene> Build() {
    const uint32_t w = scene_.film().width(), h = scene_.film().height();
    kernel_ = std::make_unique<KernelScene>(sources_.device, Camera(scene_.camera(), w, h), w, h);
    if (sources_.stop) kernel_->StopWhen(*sources_.stop);
    switch (scene_.light_sampler()) {
      case v1::Scene::LIGHT_SAMPLER_UNIFORM:
        kernel_->ChooseLights(KernelScene::LightChoice::kUniform);
        break;
      case v1::Scene::LIGHT_SAMPLER_BVH:
        kernel_->ChooseLights(KernelScene::LightChoice::kBvh);
        break;
      default:
        kernel_->ChooseLights(KernelScene::LightChoice::kPower);
    }
    kernel_->SampleSpheresByArea(scene_.sphere_sampling() == v1::Scene::SPHERE_SAMPLING_AREA);
    kernel_->SampleTrianglesBySolidAngle(scene_.triangle_sampling() == v1::Scene::TRIANGLE_SAMPLING_SOLID_ANGLE);
    // In order: a texture may refer to those before it.
    for (const v1::SceneTexture& t : scene_.textures()) {
      kernel_->ThrowIfStopped();
      textures_[t.name()] = MakeTexture(t);
    }
    bool remote_materials = false;
    for (const v1::Material& m : scene_.materials()) {
      const std::string what = MaterialName(m);
      // In order: a material may wrap one before it.
      std::shared_ptr<const SurfaceModel> model = Create<SurfaceModel>(m.class_name(), m.properties(), m.address(), what);
      remote_materials = remote_materials || dynamic_cast<const Remote<SurfaceModel>*>(model.get());
      models_[m.name()] = model;
      materials_[m.name()] = kernel_->AddMaterial(std::move(model));
    }
    // Footprints are made for the textures that filter over them and for
    // materials in other processes, which may filter their own.
    bool footprints_read = remote_materials, positions_read = remote_materials;
    for (const auto& [name, texture] : textures_) {
      footprints_read = footprints_read || texture->ReadsFootprints();
      positions_read = positions_read || texture->ReadsPositions();
    }
    kernel_->ReadFootprints(footprints_read);
    kernel_->ReadPositions(positions_read);
    for (const v1::SceneMedium& m : scene_.media()) {
      const std::string what = MediumName(m);
      ResolvedProperties own{&textures_, nullptr, {}};
      const v1::Properties props = WithoutFile(m.medium(), what, own);
      media_[m.name()] = kernel_->AddMedium(Create<Medium>(m.medium().class_name(), props, m.medium().address(), what, &own));
    }
    kernel_->SetCameraMedium(MediumNumber(scene_.camera_medium()));
    for (int i = 0; i < scene_.lights_size(); ++i) {
      const v1::Light& light = scene_.lights(i);
      const std::string what = LightName(light, i);
      ResolvedProperties own{&textures_, nullptr, {}};
      const v1::Properties props = WithoutFile(light.emitter(), what, own);
      const Emitter* emitter =
          kernel_->AddEmitter(Create<Emitter>(light.emitter().class_name(), props, light.emitter().address(), what, &own));
      const Transform to_world =
          light.has_to_world() ? FromProto(light.to_world(), what + " to_world") : Transform{};
      switch (light.kind()) {
        case v1::Light::DIRECTIONAL:
          kernel_->AddDirectionalLight(emitter, to_world);
          break;
        case v1::Light::ENVIRONMENT:
          kernel_->AddEnvironment(emitter, to_world);
          break;
        default:
          kernel_->AddLight(emitter, to_world);
      }
    }
    UseAggregate(KernelScene::kWorld, scene_.aggregate(), "scene aggregate");
    AddShapes(KernelScene::kWorld, scene_.shapes(), "", scene_.aggregate());
    for (const v1::Group& g : scene_.groups()) {
      groups_[g.name()] = {&g, kernel_->NewGroup()};
      const v1::ComponentSpec& aggregate = g.has_aggregate() ? g.aggregate() : scene_.aggregate();
      UseAggregate(groups_[g.name()].second, aggregate, "group '" + g.name() + "' aggregate");
      AddShapes(groups_[g.name()].second, g.shapes(), "group '" + g.name() + "' ", aggregate);
    }
    for (const v1::Instance& instance : scene_.instances()) Place(instance, Transform{}, 1);
    kernel_->Commit();
    return std::move(kernel_);
  }

 private:
  template <typename I>
  std::unique_ptr<I> Create(const std::string& class_name, const v1::Properties& props, const std::string& address,
                            const std::string& what, const ResolvedProperties* resolved = nullptr) {
    try {
      return MakeComponent<I>(sources_.components, class_name, props, address,
                              resolved ? resolved : &scene_references_);
    } catch (const Error& e) {
      throw Error(what + ": " + e.what());
    }
  }

  // A component's properties without its files (IsFileKey, IsAssetKey),
  // which `own` names for it by their `filename` keys.
  v1::Properties WithoutFile(const v1::ComponentSpec& spec, const std::string& what, ResolvedProperties& own) {
    v1::Properties props = spec.properties();
    auto& values = *props.mutable_values();
    for (auto it = values.begin(); it != values.end();) {
      const std::string& key = it->first;
      if (IsFileKey(key)) {
        if (it->second.value_case() != v1::Property::kStringValue)
          throw Error(what + ": property '" + key + "' must be a string");
        if (own.files.count(key)) throw Error(what + ": a file and an asset are both given for '" + key + "'");
        own.files[key] = ConfinedPath(sources_.asset_root, it->second.string_value(), "file", what);
      } else if (IsAssetKey(key)) {
        if (!sources_.assets) throw Error(what + ": this server keeps no assets");
        const std::string file_key = FileKeyOfAsset(key);
        if (own.files.count(file_key)) throw Error(what + ": a file and an asset are both given for '" + file_key + "'");
        own.files[file_key] = sources_.assets->FileOf(it->second.string_value());
      } else {
        ++it;
        continue;
      }
      it = values.erase(it);
    }
    return props;
  }

  // A group's own instance of the aggregate class `spec` names, if any.
  void UseAggregate(uint32_t group, const v1::ComponentSpec& spec, const std::string& what) {
    if (spec.class_name().empty()) return;
    kernel_->SetAggregate(group, Create<Aggregate>(spec.class_name(), spec.properties(), spec.address(),
                                                   what + " (" + spec.class_name() + ")"));
  }

  // A texture of the scene, its file found for it.
  std::shared_ptr<const Texture> MakeTexture(const v1::SceneTexture& t) {
    const std::string what = TextureName(t);
    ResolvedProperties own{&textures_, nullptr, {}};
    const v1::Properties props = WithoutFile(t.texture(), what, own);
    return Create<Texture>(t.texture().class_name(), props, t.texture().address(), what, &own);
  }

  // `aggregate`: the group's, which a moving shape's group of its own takes too.
  void AddShapes(uint32_t group, const google::protobuf::RepeatedPtrField<v1::SceneShape>& shapes,
                 const std::string& where, const v1::ComponentSpec& aggregate) {
    for (int i = 0; i < shapes.size(); ++i) {
      kernel_->ThrowIfStopped();  // between meshes, which may take a while to parse
      const v1::SceneShape& s = shapes[i];
      const std::string what = where + ShapeName(s, i);
      ShapeLook look;
      look.name = s.name().empty() ? what : s.name();
      look.material = materials_.at(s.material());
      look.flip_normals = s.flip_normals();
      look.flip_winding = s.flip_winding();
      if (!s.interior().empty() || !s.exterior().empty())
        look.media = {MediumNumber(s.interior()), MediumNumber(s.exterior()), true};
      if (!s.alpha().empty()) {
        const auto alpha = textures_.find(s.alpha());
        if (alpha == textures_.end()) throw Error(what + ": alpha names no texture of the scene");
        look.alpha = alpha->second;
      }
      if (s.has_emitter())
        look.emitter = kernel_->AddEmitter(
            Create<Emitter>(s.emitter().class_name(), s.emitter().properties(), s.emitter().address(),
                           what + " emitter"));
      const Transform to_world = ShapeTransform(s, what);
      if (s.has_to_world_end()) {
        // Embree moves instances: a moving shape is one in a group of its own.
        const uint32_t own = kernel_->NewGroup();
        UseAggregate(own, aggregate, what + " aggregate");
        kernel_->AddPlacement(own, to_world, FromProto(s.to_world_end(), what + " to_world_end"));
        AddShape(own, s, look, Transform{}, what);
        continue;
      }
      const uint32_t id = AddShape(group, s, look, to_world, what);
      // ValidateMeter made sure this is the one world shape of that name.
      if (group == KernelScene::kWorld && scene_.camera().model() == v1::Camera::IRRADIANCE_METER &&
          s.name() == scene_.camera().meter_shape())
        kernel_->SetMeterShape(id);
    }
  }

  // The shape's geometry, moved to where `to_world` puts it; its number
  // in the group.
  uint32_t AddShape(uint32_t group, const v1::SceneShape& s, const ShapeLook& look, const Transform& to_world,
                    const std::string& what) {
    if (s.has_curves()) {
      // Radii scale as spheres' do, by the cube root of the determinant.
      CurveGeometry curves = CurvesOf(s.curves());
      const float scale = float(std::cbrt(std::abs(to_world.Determinant3())));
      for (auto& point : curves.points) {
        const Vec3 p = to_world.Point(Vec3(point[0], point[1], point[2]));
        point = {p.x, p.y, p.z, point[3] * scale};
      }
      return kernel_->AddCurves(group, std::move(curves), look);
    }
    if (s.has_sphere()) {
      const auto& c = s.sphere().center();
      const float scale = float(std::cbrt(std::abs(to_world.Determinant3())));
      // Its uv follows its own axes, rotated (and perhaps mirrored) by to_world.
      std::array<Vec3, 3> axes{Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
      for (Vec3& axis : axes) axis = Normalize(to_world.Vector(axis));
      return kernel_->AddSphere(group, to_world.Point(Vec3(float(c.x()), float(c.y()), float(c.z()))),
                                float(s.sphere().radius()) * scale, look, axes);
    }
    TriangleMesh mesh = s.has_mesh() ? LoadMesh(s.mesh(), what) : Rectangle();
    for (Vec3& p : mesh.positions) p = to_world.Point(p);
    for (Vec3& n : mesh.normals) {
      const Vec3 moved = to_world.Normal(n);
      const float length = Length(moved);
      n = length > 0 ? moved / length : Vec3();
    }
    return kernel_->AddMesh(group, std::move(mesh), look);
  }

  TriangleMesh LoadMesh(const v1::Mesh& mesh, const std::string& what) {
    TriangleMesh out = ReadMesh(mesh, what);  // validated
    if (mesh.smooth_normals() && !mesh.face_normals() && out.normals.empty()) out.normals = AngleWeightedNormals(out);
    return out;
  }

  TriangleMesh ReadMesh(const v1::Mesh& mesh, const std::string& what) {
    const MeshOptions options{mesh.has_flip_tex_coords() ? mesh.flip_tex_coords() : true, mesh.face_normals()};
    switch (mesh.source_case()) {
      case v1::Mesh::kFile:
      case v1::Mesh::kAsset:
        return ParseMesh(ReadMeshBytes(mesh, sources_.asset_root, sources_.assets, what), MeshFormat(mesh),
                         mesh.source_case() == v1::Mesh::kFile ? mesh.file() : what, options);
      case v1::Mesh::kData:
        return ParseMesh(mesh.data(), mesh.format(), what, options);
      default:
        return InlineMesh(mesh, what);
    }
  }

  static TriangleMesh InlineMesh(const v1::Mesh& mesh, const std::string& what) {
    TriangleMesh out;
    for (int i = 0; i + 2 < mesh.positions_size(); i += 3)
      out.positions.emplace_back(mesh.positions(i), mesh.positions(i + 1), mesh.positions(i + 2));
    out.indices.assign(mesh.indices().begin(), mesh.indices().end());
    if (mesh.normals_size() % 3 != 0) throw Error(what + ": inline mesh normals need xyz triples");
    if (!mesh.face_normals())
      for (int i = 0; i + 2 < mesh.normals_size(); i += 3)
        out.normals.emplace_back(mesh.normals(i), mesh.normals(i + 1), mesh.normals(i + 2));
    out.uvs.assign(mesh.uvs().begin(), mesh.uvs().end());
    for (const v1::MeshAttribute& a : mesh.attributes())
      out.attributes.push_back({a.name(), a.channels(), {a.values().begin(), a.values().end()}});
    ValidateMesh(out, what);
    return out;
  }

  // Mitsuba's rectangle: [-1, 1]² in z = 0, facing +z, uv from the corner
  // (-1, -1).
  static TriangleMesh Rectangle() {
    TriangleMesh m;
    m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    m.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
  }

  // Embree here instances one level deep: nested placements are flattened
  // into world placements with composed transforms.
  void Place(const v1::Instance& instance, const Transform& parent, int depth) {
    const auto& [group, index] = groups_.at(instance.group());
    const std::string what = "instance of '" + instance.group() + "'";
    const Transform to_world =
        parent * (instance.has_to_world() ? FromProto(instance.to_world(), what) : Transform{});
    // Each level is sound (ValidateScene); their product may not be.
    CheckPlacement(to_world, what + " (composed with the instances around it)");
    if (group->shapes_size() > 0) kernel_->AddPlacement(index, to_world);
    for (const v1::Instance& child : group->instances()) Place(child, to_world, depth + 1);
  }

  const v1::Scene& scene_;
  const SceneSources& sources_;
  std::unique_ptr<KernelScene> kernel_;
  // A medium by name; kNoMedium for none.
  uint32_t MediumNumber(const std::string& name) const { return name.empty() ? kNoMedium : media_.at(name); }

  std::map<std::string, uint32_t> materials_;
  std::map<std::string, uint32_t> media_;
  std::map<std::string, std::pair<const v1::Group*, uint32_t>> groups_;
  // The scene's textures and surface models by name, for the components
  // that refer to them (scene_references_: textures and models both).
  std::map<std::string, std::shared_ptr<const Texture>> textures_;
  std::map<std::string, std::shared_ptr<const SurfaceModel>> models_;
  const ResolvedProperties scene_references_{&textures_, &models_, {}};
};

void CheckInstance(const v1::Instance& instance) {
  const std::string what = "instance of '" + instance.group() + "'";
  if (instance.has_to_world()) CheckPlacement(FromProto(instance.to_world(), what), what);
}

// Counts the world placements nested instancing expands to, rejecting
// cycles, missing groups and explosive nesting before anything is built.
uint64_t CountPlacements(const v1::Scene& scene) {
  std::map<std::string, const v1::Group*> groups;
  for (const v1::Group& g : scene.groups()) {
    if (g.name().empty()) throw Error("a group has no name");
    if (!groups.emplace(g.name(), &g).second) throw Error("group '" + g.name() + "' defined twice");
  }
  std::map<std::string, uint64_t> memo;
  std::set<std::string> visiting;
  std::function<uint64_t(const std::string&, int)> count = [&](const std::string& name, int depth) -> uint64_t {
    auto it = groups.find(name);
    if (it == groups.end()) throw Error("instance of unknown group '" + name + "'");
    if (depth > SceneLimits::kMaxInstanceDepth)
      throw Error("instancing nested deeper than " + std::to_string(SceneLimits::kMaxInstanceDepth) + " levels");
    if (visiting.count(name)) throw Error("group '" + name + "' instances itself");
    if (memo.count(name)) return memo[name];
    visiting.insert(name);
    uint64_t n = 1;
    for (const v1::Instance& child : it->second->instances()) {
      CheckInstance(child);
      n = std::min<uint64_t>(n + count(child.group(), depth + 1), SceneLimits::kMaxPlacements + 1);
    }
    visiting.erase(name);
    return memo[name] = n;
  };
  uint64_t total = 0;
  for (const v1::Instance& instance : scene.instances()) {
    CheckInstance(instance);
    total = std::min<uint64_t>(total + count(instance.group(), 1), SceneLimits::kMaxPlacements + 1);
  }
  return total;
}

// A meter's film is one pixel that every sample reaches with the same
// weight (a box of at least half a pixel); an irradiance meter measures on
// one shape of the world that stays put.
void ValidateMeter(const v1::Scene& scene) {
  const v1::Camera& camera = scene.camera();
  if (camera.model() != v1::Camera::RADIANCE_METER && camera.model() != v1::Camera::IRRADIANCE_METER) return;
  const v1::ReconstructionFilter& filter = scene.film().filter();
  const auto below_half = [](double radius) { return radius != 0 && radius < 0.5; };
  if (filter.kind() != v1::ReconstructionFilter::BOX || below_half(filter.radius()) || below_half(filter.radius_y()))
    throw Error("film: a meter needs the box filter of radius 0.5 or more, so that every sample weighs the same");
  if (camera.model() != v1::Camera::IRRADIANCE_METER) return;
  int found = 0;
  for (const v1::SceneShape& shape : scene.shapes())
    if (shape.name() == camera.meter_shape()) {
      if (++found > 1) throw Error("camera: meter_shape '" + camera.meter_shape() + "' names two shapes");
      if (shape.has_to_world_end())
        throw Error("camera: the irradiance meter's shape '" + camera.meter_shape() + "' moves: it must stay put");
    }
  if (found == 0)
    throw Error("camera: meter_shape '" + camera.meter_shape() + "' is not a shape of Scene.shapes");
}

}  // namespace

std::vector<std::string> SceneAssets(const v1::Scene& scene) {
  std::vector<std::string> hashes;
  for (const auto& [what, spec] : FileComponents(scene))
    for (const auto& [key, asset] : AssetsOf(*spec))
      if (asset->value_case() == v1::Property::kStringValue) hashes.push_back(asset->string_value());
  const auto collect = [&](const google::protobuf::RepeatedPtrField<v1::SceneShape>& shapes) {
    for (const v1::SceneShape& shape : shapes)
      if (shape.has_mesh() && shape.mesh().has_asset()) hashes.push_back(shape.mesh().asset());
  };
  collect(scene.shapes());
  for (const v1::Group& group : scene.groups()) collect(group.shapes());
  return hashes;
}

std::string MeshFormat(const v1::Mesh& mesh) {
  if (!mesh.format().empty() || mesh.source_case() != v1::Mesh::kFile) return mesh.format();
  std::filesystem::path file = mesh.file();
  if (file.extension() == ".gz") file = file.stem();  // x.ply.gz: a compressed x.ply
  const std::string ext = file.extension().string();
  return ext.empty() ? ext : ext.substr(1);
}

std::string ReadMeshBytes(const v1::Mesh& mesh, const std::filesystem::path& asset_root, const AssetSource* assets,
                          const std::string& what) {
  if (mesh.source_case() == v1::Mesh::kAsset) {
    if (!assets) throw Error(what + ": mesh asset " + mesh.asset() + ": this server keeps no assets");
    return assets->Read(mesh.asset());
  }
  const std::filesystem::path path = ConfinedPath(asset_root, mesh.file(), "mesh file", what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(what + ": mesh file '" + mesh.file() + "' not found");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

std::vector<std::filesystem::path> ComponentFiles(const v1::Scene& scene, const std::filesystem::path& asset_root,
                                                  const AssetSource* assets) {
  std::vector<std::filesystem::path> files;
  for (const auto& [what, spec] : FileComponents(scene))
    for (const auto& [key, value] : spec->properties().values()) {
      if (value.value_case() != v1::Property::kStringValue) continue;
      try {
        if (IsFileKey(key)) files.push_back(ConfinedPath(asset_root, value.string_value(), "file", what));
        if (IsAssetKey(key) && assets && IsSha256(value.string_value()) && assets->Has(value.string_value()))
          files.push_back(assets->FileOf(value.string_value()));
      } catch (const Error&) {
        // Not resolvable: the build says so.
      }
    }
  return files;
}

bool IsSha256(const std::string& text) {
  const auto hex = [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); };
  return text.size() == 64 && std::all_of(text.begin(), text.end(), hex);
}

void ValidateScene(const v1::Scene& scene, const AssetSource* assets) {
  const v1::Film& film = scene.film();
  if (film.width() == 0 || film.height() == 0 || film.width() > SceneLimits::kMaxFilmSide ||
      film.height() > SceneLimits::kMaxFilmSide ||
      uint64_t(film.width()) * film.height() > SceneLimits::kMaxPixels)
    throw Error("film resolution " + std::to_string(film.width()) + "x" + std::to_string(film.height()) +
                " is out of range (1 to " + std::to_string(SceneLimits::kMaxFilmSide) +
                " per side, at most " + std::to_string(SceneLimits::kMaxPixels) + " pixels)");
  // Built here so that Submit refuses an unknown kind or a bad radius
  // (Error naming the field) rather than the job failing later.
  ReconstructionFilter{film.filter()};
  if (!(std::isfinite(film.exposure()) && film.exposure() >= 0 && film.exposure() <= 1e12))
    throw Error("film.exposure " + std::to_string(film.exposure()) + " is out of range (0 to 1e12; 0 means 1)");
  if (!(std::isfinite(film.max_component_value()) && film.max_component_value() >= 0))
    throw Error("film.max_component_value " + std::to_string(film.max_component_value()) +
                " must be finite and not negative (0: no limit)");
  if (!scene.has_camera()) throw Error("scene has no camera");
  Camera(scene.camera(), film.width(), film.height());
  ValidateMeter(scene);
  SceneNames names;
  for (const v1::Material& m : scene.materials()) {
    if (m.name().empty()) throw Error("a material has no name");
    if (m.class_name().empty()) throw Error("material '" + m.name() + "' has no class");
    if (!names.materials.insert(m.name()).second) throw Error("material '" + m.name() + "' defined twice");
  }
  for (const v1::SceneTexture& t : scene.textures()) {
    if (t.name().empty()) throw Error("a texture has no name");
    if (t.texture().class_name().empty()) throw Error("texture '" + t.name() + "' has no class");
    if (!names.textures.insert(t.name()).second) throw Error("texture '" + t.name() + "' defined twice");
  }
  for (const v1::SceneMedium& m : scene.media()) {
    if (m.name().empty()) throw Error("a medium has no name");
    if (m.medium().class_name().empty()) throw Error("medium '" + m.name() + "' has no class");
    if (!names.media.insert(m.name()).second) throw Error("medium '" + m.name() + "' defined twice");
  }
  CheckReferenceTrees(scene);
  if (!scene.camera_medium().empty() && !names.media.count(scene.camera_medium()))
    throw Error("camera_medium '" + scene.camera_medium() + "' is not a medium of the scene");
  for (const auto& [what, spec] : FileComponents(scene))
    for (const auto& [key, asset] : AssetsOf(*spec))
      if (asset->value_case() != v1::Property::kStringValue || !IsSha256(asset->string_value()))
        throw Error(what + ": property '" + key + "' must be a SHA-256 (64 lowercase hex digits)");
  ValidateShapes(scene.shapes(), names, "");
  int environments = 0;
  for (int i = 0; i < scene.lights_size(); ++i) {
    const v1::Light& light = scene.lights(i);
    if (light.emitter().class_name().empty()) throw Error(LightName(light, i) + " has no emitter class");
    // Rays that leave the scene see one environment.
    if (light.kind() == v1::Light::ENVIRONMENT && ++environments > 1)
      throw Error(LightName(light, i) + ": a scene has at most one ENVIRONMENT light");
    if (light.has_to_world())
      CheckPlacement(FromProto(light.to_world(), LightName(light, i) + " to_world"), LightName(light, i));
  }
  for (const v1::Group& g : scene.groups())
    ValidateShapes(g.shapes(), names, "group '" + g.name() + "' ");
  if (CountPlacements(scene) > SceneLimits::kMaxPlacements)
    throw Error("instancing expands to more than " + std::to_string(SceneLimits::kMaxPlacements) + " placements");
  if (!assets) return;
  for (const auto& [what, spec] : FileComponents(scene))
    for (const auto& [key, asset] : AssetsOf(*spec))
      if (!assets->Has(asset->string_value()))
        throw Error(what + ": asset " + asset->string_value() +
                    " is not on this server; upload it with AssetService.Upload before submitting");
  RequireShapeAssets(scene.shapes(), *assets, "");
  for (const v1::Group& g : scene.groups()) RequireShapeAssets(g.shapes(), *assets, "group '" + g.name() + "' ");
}

std::unique_ptr<KernelScene> BuildScene(const v1::Scene& scene, const SceneSources& sources) {
  ValidateScene(scene, sources.assets);
  return Builder(scene, sources).Build();
}

}  // namespace yarf
