// pbrt shapes (with their area lights), placed in the world or in the
// object being defined.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>

#include "importers/curve_shapes.h"
#include "importers/loop_subdivision.h"
#include "importers/mesh_shapes.h"
#include "importers/pbrt_importer.h"
#include "importers/properties_util.h"
#include "importers/scene_folder.h"

namespace yarf::importers {
namespace {

// Orders each triangle so that its winding agrees with the mean of its
// vertex normals: pbrt turns the geometric normal toward N when N is given.
void OrientByNormals(const std::vector<double>& p, const std::vector<double>& n, std::vector<uint32_t>& indices) {
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const uint32_t a = indices[t], b = indices[t + 1], c = indices[t + 2];
    auto point = [&](uint32_t i) { return Vec3d{p[3 * i], p[3 * i + 1], p[3 * i + 2]}; };
    auto normal = [&](uint32_t i) { return Vec3d{n[3 * i], n[3 * i + 1], n[3 * i + 2]}; };
    const Vec3d winding = Cross(point(b) - point(a), point(c) - point(a));
    if (Dot(winding, normal(a) + normal(b) + normal(c)) < 0) std::swap(indices[t + 1], indices[t + 2]);
  }
}

// Whether a PLY file's header gives its vertices normals (a property nx
// of element vertex): the first 64 KiB of the file hold any real header.
bool PlyHasVertexNormals(const std::filesystem::path& file, const SourceLocation& where) {
  std::istringstream header(ReadFileHead(file, size_t(64) << 10, where));
  std::string line, element;
  while (std::getline(header, line)) {
    std::istringstream words(line);
    std::string keyword, a, b;
    words >> keyword >> a >> b;
    if (keyword == "end_header") break;
    if (keyword == "element") element = a;
    if (keyword == "property" && element == "vertex" && b == "nx") return true;
  }
  return false;
}

}  // namespace

TriangleArrays PbrtImporter::Subdivided(const std::vector<double>& p, const std::vector<uint32_t>& indices,
                                        PbrtParams& params, const SourceLocation& where) {
  // pbrt-v4 names the levels "levels"; pbrt-v3 (and its scenes) "nlevels".
  const char* key = params.Has("nlevels") && !params.Has("levels") ? "nlevels" : "levels";
  const int64_t asked = params.Integer(key, 3);
  if (asked < 0 || asked > 16) Fail(params.WhereIs(key, where), "loopsubdiv: levels must be 0 to 16");
  const int levels = LoopLevels(indices.size() / 3, int(asked));
  if (levels < asked)
    Warn(params.WhereIs(key, where), "loopsubdiv-levels",
         "loopsubdiv: " + std::to_string(levels) + " levels instead of " + std::to_string(asked) + " (at most " +
             std::to_string(kLoopTriangles) + " triangles)");
  try {
    return LoopSubdivision(p, indices, levels);
  } catch (const std::runtime_error& e) {
    Fail(where, std::string("loopsubdiv: ") + e.what());
  }
}

void PbrtImporter::Shape(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  // pbrt-v4 skips surfaces of the interface material where no medium changes.
  const bool interface = state_.material == kInterface;
  auto interface_light = [&] {
    if (interface && state_.area_light)
      Warn(state_.area_light->where, "interface-area-light",
           "area light on a shape of the interface material ignored (as pbrt-v4 does)");
  };
  if (interface && state_.inside_medium == state_.outside_medium) return interface_light();
  v1::SceneShape shape;
  Matrix4 to_world = state_.ctm;
  NormalRule rule = NormalRule::kTransformed;
  bool flip = state_.reverse_orientation;
  const std::string what = "shape '" + type + "'";
  // The areas of the pbrt-v4 shapes this one is made of, for an area
  // light's power: a triangle mesh's triangles after the CTM, the
  // quadrics' as pbrt-v4 gives them (in object space, partial as given).
  std::vector<double> light_areas;
  if (type == "trianglemesh" || type == "bilinearmesh" || type == "loopsubdiv") {
    // A bilinear patch has four corners where a triangle has three; a
    // subdivision surface's control mesh has neither normals nor uv.
    const bool patches = type == "bilinearmesh", subdivided = type == "loopsubdiv";
    const size_t corners = patches ? 4 : 3;
    const std::vector<double> p = params.Numbers("P", {"point3"});
    std::vector<double> raw = params.Numbers("indices", {"integer"});
    const std::vector<double> n = subdivided ? std::vector<double>() : params.Numbers("N", {"normal3"});
    if (p.empty() || p.size() % 3 != 0) Fail(params.WhereIs("P", where), what + ": P needs xyz triples");
    const size_t vertices = p.size() / 3;
    if (raw.empty() && vertices == corners) {
      raw = {0, 1, 2};
      if (patches) raw.push_back(3);
    }
    if (raw.empty() || raw.size() % corners != 0)
      Fail(params.WhereIs("indices", where),
           what + (patches ? ": indices needs four per patch" : ": indices needs triples"));
    std::vector<uint32_t> indices;
    indices.reserve(raw.size());
    for (double i : raw) {
      if (!(i >= 0 && i < double(vertices)) || i != std::floor(i))
        Fail(params.WhereIs("indices", where),
             what + ": index " + std::to_string(int64_t(std::clamp(i, -9e18, 9e18))) + " is not a vertex of P");
      indices.push_back(uint32_t(i));
    }
    if (!n.empty() && n.size() != p.size()) Fail(params.WhereIs("N", where), what + ": N needs one normal per vertex");
    std::vector<double> uv = subdivided ? std::vector<double>() : params.Numbers("uv", {"point2", "float"});
    if (uv.empty() && !subdivided) uv = params.Numbers("st", {"point2", "float"});
    if (!uv.empty() && uv.size() != 2 * vertices)
      Fail(params.WhereIs(params.Has("uv") ? "uv" : "st", where), what + ": uv needs one (u, v) per vertex");
    TriangleArrays mesh_arrays = patches      ? BilinearPatches(p, indices, n, uv)
                                 : subdivided ? Subdivided(p, indices, params, where)
                                              : TriangleArrays{p, n, uv, std::move(indices)};
    if (!mesh_arrays.normals.empty()) {
      OrientByNormals(mesh_arrays.positions, mesh_arrays.normals, mesh_arrays.indices);
      // pbrt-v4 faces a mesh with normals as they face, ReverseOrientation
      // or not.
      flip = false;
    }
    if (state_.area_light) {
      // pbrt-v4 makes a light of each triangle, and of each patch.
      const std::vector<double>& q = mesh_arrays.positions;
      const std::vector<uint32_t>& t = mesh_arrays.indices;
      auto point = [&](uint32_t i) { return to_world.Point({q[3 * i], q[3 * i + 1], q[3 * i + 2]}); };
      auto area = [&](size_t k) { return TriangleArea(point(t[3 * k]), point(t[3 * k + 1]), point(t[3 * k + 2])); };
      const size_t triangles = t.size() / 3;
      if (mesh_arrays.face_triangles.empty()) {
        for (size_t k = 0; k < triangles; ++k) light_areas.push_back(area(k));
      } else {
        size_t k = 0;
        for (const uint32_t count : mesh_arrays.face_triangles) {
          double face = 0;
          for (const size_t end = k + count; k < end; ++k) face += area(k);
          light_areas.push_back(face);
        }
      }
    }
    const std::vector<float> positions(mesh_arrays.positions.begin(), mesh_arrays.positions.end());
    v1::Mesh inline_mesh = InlineMesh(positions, mesh_arrays.indices);
    v1::Mesh& mesh = *shape.mutable_mesh() =
        patches || subdivided ? assembly_.Made(std::move(inline_mesh), where) : std::move(inline_mesh);
    mesh.mutable_normals()->Add(mesh_arrays.normals.begin(), mesh_arrays.normals.end());
    mesh.mutable_uvs()->Add(mesh_arrays.uvs.begin(), mesh_arrays.uvs.end());
    if (params.Has("S")) {
      params.Find("S");
      Warn(params.WhereIs("S", where), "trianglemesh-S", "per-vertex tangents (S) are not supported: ignored");
    }
    // pbrt-v4 samples a bilinear mesh's area light by its emission image:
    // a way of sampling, the light it gives is the same.
    params.Accept({"faceIndices", "emissionfilename"});
  } else if (type == "plymesh") {
    const std::string name = params.String("filename", "");
    const auto file = folder_.Resolve(name, origin_.file, params.WhereIs("filename", where));
    // pbrt reads .ply and gzip-compressed .ply.gz files; yarf's mesh reader
    // inflates the latter itself.
    const std::string ending = file.extension() == ".gz" ? file.stem().extension().string() : file.extension().string();
    if (ending != ".ply") {
      Warn(params.WhereIs("filename", where), "plymesh-format",
           "plymesh: '" + name + "' is not a .ply or .ply.gz file: ignored");
      return;
    }
    shape.mutable_mesh()->set_file(folder_.Relative(file));
    shape.mutable_mesh()->set_format("ply");
    // As a trianglemesh with N, a mesh with normals faces as they do.
    if (flip && PlyHasVertexNormals(file, params.WhereIs("filename", where))) flip = false;
    for (const char* key : {"displacement", "edgelength"})
      if (params.Has(key)) {
        params.Find(key);
        Warn(params.WhereIs(key, where), "plymesh-displacement", "plymesh displacement is not supported: ignored");
      }
  } else if (type == "sphere") {
    const double radius = params.Float("radius", 1);
    if (!(radius > 0 && radius < 1e30)) Fail(params.WhereIs("radius", where), "sphere radius must be positive");
    const double z0 = std::clamp(params.Float("zmin", -radius), -radius, radius);
    const double z1 = std::clamp(params.Float("zmax", radius), -radius, radius);
    const double zmin = std::min(z0, z1), zmax = std::max(z0, z1);
    const double phimax = std::clamp(params.Float("phimax", 360), 0.0, 360.0);
    if (!(zmax > zmin) || !(phimax > 0)) {
      Warn(where, "empty-sphere", "a partial sphere of no area (zmin = zmax or phimax = 0): left out");
      return;
    }
    light_areas.push_back(phimax * M_PI / 180 * radius * (zmax - zmin));
    if (zmin > -radius || zmax < radius || phimax < 360) {
      // A zone or wedge of the sphere: meshed, with pbrt's uv.
      *shape.mutable_mesh() = assembly_.Made(SphereZoneMesh(zmin / radius, zmax / radius, phimax), where);
      to_world = to_world * Matrix4::Scale({radius, radius, radius});
      Warn(where, "partial-sphere",
           "partial spheres (zmin, zmax, phimax) are meshed, " + std::to_string(kCylinderSegments) +
               " quads per turn and per half turn");
    } else {
      rule = NormalRule::kSphere;
      shape.mutable_sphere()->set_radius(radius);
      shape.mutable_sphere()->mutable_center();
      // yarf's sphere has v = θ/π from its z axis (Mitsuba's); pbrt's has
      // v = 1 − θ/π. Mirrored in z, the same sphere has pbrt's.
      to_world = to_world * Matrix4::Scale({1, 1, -1});
    }
  } else if (type == "disk") {
    const double radius = params.Float("radius", 1), height = params.Float("height", 0);
    if (!(radius > 0 && radius < 1e30)) Fail(params.WhereIs("radius", where), "disk radius must be positive");
    const double inner = std::clamp(params.Float("innerradius", 0), 0.0, radius);
    const double phimax = std::clamp(params.Float("phimax", 360), 0.0, 360.0);
    if (!(inner < radius) || !(phimax > 0)) {
      Warn(where, "empty-disk", "a partial disk of no area (innerradius = radius or phimax = 0): left out");
      return;
    }
    light_areas.push_back(phimax * M_PI / 180 / 2 * (radius * radius - inner * inner));
    *shape.mutable_mesh() = assembly_.Made(DiskMesh(DiskUv::kPbrt, inner / radius, phimax), where);
    to_world = to_world * Matrix4::Translate({0, 0, height}) * Matrix4::Scale({radius, radius, 1});
    Warn(where, "disk", "disk shapes are meshed as fans of " + std::to_string(kDiskSegments) + " triangles");
  } else if (type == "cylinder") {
    const double radius = params.Float("radius", 1), zmin = params.Float("zmin", -1), zmax = params.Float("zmax", 1);
    const double phimax = params.Float("phimax", 360);
    if (!(radius > 0 && radius < 1e30)) Fail(params.WhereIs("radius", where), "cylinder radius must be positive");
    if (!(zmax > zmin && zmax - zmin < 1e30)) Fail(params.WhereIs("zmax", where), "cylinder zmax must exceed zmin");
    if (!(phimax > 0 && phimax <= 360)) Fail(params.WhereIs("phimax", where), "cylinder phimax must lie in (0, 360]");
    *shape.mutable_mesh() = assembly_.Made(CylinderMesh(phimax), where);
    light_areas.push_back((zmax - zmin) * radius * phimax * M_PI / 180);
    to_world = to_world * Matrix4::Translate({0, 0, zmin}) * Matrix4::Scale({radius, radius, zmax - zmin});
    Warn(where, "cylinder",
         "cylinder shapes are meshed as tubes of " + std::to_string(kCylinderSegments) + " quads per turn");
  } else if (type == "curve") {
    rule = NormalRule::kSphere;
    const double width = params.Float("width", 1);
    const std::vector<double> p = params.Numbers("P", {"point3"});
    v1::Curves& curves = *shape.mutable_curves() =
        PbrtCurve(p, int(std::clamp<int64_t>(params.Integer("degree", 3), -1, 4)), params.String("basis", "bezier"),
                  params.Float("width0", width), params.Float("width1", width), where);
    const std::string form = params.String("type", "flat");
    if (form == "cylinder") {
      curves.set_form(v1::Curves::FORM_ROUND);
    } else if (form == "flat" || form == "ribbon") {
      curves.set_form(v1::Curves::FORM_FLAT);
      if (form == "ribbon") {
        params.Find("N");
        Warn(params.WhereIs("type", where), "curve-ribbon",
             "ribbon curves face each ray: their orientation (N) is not followed");
      }
    } else {
      Fail(params.WhereIs("type", where), "curve: type must be \"flat\", \"ribbon\" or \"cylinder\"");
    }
    // pbrt splits curves to bound them; Embree intersects them whole.
    params.Accept({"splitdepth"});
  } else {
    static const std::vector<std::string> kKnown = {"trianglemesh", "bilinearmesh", "plymesh", "sphere", "disk",
                                                    "cylinder", "loopsubdiv", "curve"};
    Warn(where, "shape:" + type, "shape '" + type + "' is not supported: ignored" + DidYouMean(type, kKnown));
    return;
  }
  if (params.Has("alpha")) {
    const Textured alpha = TexturedFloat(params, "alpha", 1);
    if (shape.has_sphere() || shape.has_curves()) {
      Warn(params.WhereIs("alpha", where), "alpha-" + type,
           "alpha cut-outs on " + type + " shapes are not supported: ignored");
    } else if (alpha.IsTexture()) {
      shape.set_alpha(alpha.texture);
    } else if (alpha.constant.r < 1) {
      v1::Properties props;
      SetFloat(props, "value", alpha.constant.r);
      shape.set_alpha(assembly_.AddTexture("alpha", Spec("constant_texture", std::move(props))));
    }
  }
  params.WarnUnused(diagnostics_, what);

  shape.set_material(interface                 ? assembly_.NullMaterial()
                     : state_.material.empty() ? assembly_.DefaultMaterial()
                                               : state_.material);
  SetMedia(shape);
  if (state_.area_light) {
    if (interface) {
      interface_light();
    } else if (shape.has_curves()) {
      Warn(state_.area_light->where, "curve-area-light", "area lights on curves are not supported: emission ignored");
    } else if (!object_.empty()) {
      Warn(state_.area_light->where, "instanced-area-light",
           "area lights in object instances are not supported (as in pbrt): emission ignored");
    } else {
      v1::Properties props;
      const Rgb radiance = AreaLightRadiance(light_areas, what);
      if (state_.area_light->image.empty()) {
        SetRgb(props, "radiance", radiance);
      } else {
        v1::Properties image;
        SetString(image, "filename", folder_.Relative(state_.area_light->image));
        SetFloat(image, "scale", radiance.r);
        SetString(image, "filter", "bilinear");
        SetString(image, "wrap", "clamp");
        SetTransform(image, "to_uv", Matrix4({1, 0, 0, 0, 0, -1, 0, 1, 0, 0, 1, 0, 0, 0, 0, 1}));
        SetReference(props, "radiance", assembly_.AddTexture("arealight", Spec("bitmap", std::move(image))));
      }
      if (state_.area_light->two_sided) SetBool(props, "two_sided", true);
      *shape.mutable_emitter() = Spec("diffuse_area", std::move(props));
    }
  }
  assembly_.AddShape(std::move(shape), to_world, flip, rule, where, object_);
}

}  // namespace yarf::importers
