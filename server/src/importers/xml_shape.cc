// Mitsuba shapes, shape groups and instances.
#include <algorithm>
#include <cctype>
#include <cmath>

#include "importers/curve_shapes.h"
#include "importers/mesh_shapes.h"
#include "importers/serialized_mesh.h"
#include "importers/xml_importer.h"

namespace yarf::importers {

void MitsubaImporter::Shape(const XmlElement& e, const std::string& group) {
  const RecursionGuard guard(nesting, e.where);
  XmlPlugin p(e, *this);
  const std::string& type = p.type();
  if (type == "instance") {
    if (!group.empty()) Fail(e.where, "instances inside a shapegroup are not supported");
    Instance(p);
    return;
  }
  if (type == "shapegroup") Fail(e.where, "a shapegroup must be defined at the top level of the scene");

  v1::SceneShape shape;
  shape.set_name(e.Get("id"));
  NormalRule rule = NormalRule::kWorldWinding;
  Matrix4 cylinder_frame;  // a cylinder's unit tube to its p0, p1 and radius
  if (type == "obj" || type == "ply") {
    const std::string name = p.String("filename", "");
    const auto file = folder_.Resolve(name, e.file, p.WhereIs("filename"));
    v1::Mesh& mesh = *shape.mutable_mesh();
    mesh.set_file(folder_.Relative(file));
    mesh.set_format(type);
    mesh.set_face_normals(p.Boolean("face_normals", false));
    mesh.set_smooth_normals(true);
    mesh.set_flip_tex_coords(p.Boolean("flip_tex_coords", true));
  } else if (type == "serialized") {
    const std::string name = p.String("filename", "");
    const auto file = folder_.Resolve(name, e.file, p.WhereIs("filename"));
    const int64_t index = p.Integer("shape_index", 0);
    if (index < 0) Fail(p.WhereIs("shape_index"), "shape_index must be >= 0");
    const SerializedMesh mesh = DecodeSerializedMesh(ReadTextFile(file, e.where), uint64_t(index), e.where);
    v1::Mesh& inline_mesh = *shape.mutable_mesh() = InlineMesh(mesh.positions, mesh.indices);
    inline_mesh.mutable_normals()->Add(mesh.normals.begin(), mesh.normals.end());
    inline_mesh.mutable_uvs()->Add(mesh.uvs.begin(), mesh.uvs.end());
    if (!mesh.colors.empty()) {
      v1::MeshAttribute& colour = *inline_mesh.add_attributes();
      colour.set_name("vertex_color");
      colour.set_channels(3);
      colour.mutable_values()->Add(mesh.colors.begin(), mesh.colors.end());
    }
    inline_mesh.set_face_normals(p.Boolean("face_normals", false));
    inline_mesh.set_smooth_normals(true);
    if (shape.name().empty()) shape.set_name(mesh.name);
    if (p.Has("max_smooth_angle"))
      Warn(p.WhereIs("max_smooth_angle"), "max_smooth_angle",
           "max_smooth_angle is not supported: the file's own normals are used");
    p.Accept({"max_smooth_angle"});
  } else if (type == "sphere") {
    rule = NormalRule::kSphere;
    const Vec3d c = p.Point("center", {0, 0, 0});
    const double radius = p.Float("radius", 1);
    if (!(radius > 0 && radius < 1e30)) Fail(p.WhereIs("radius"), "sphere radius must be positive");
    v1::Sphere& sphere = *shape.mutable_sphere();
    sphere.mutable_center()->set_x(c.x), sphere.mutable_center()->set_y(c.y), sphere.mutable_center()->set_z(c.z);
    sphere.set_radius(radius);
  } else if (type == "rectangle") {
    rule = NormalRule::kTransformed;
    shape.mutable_rectangle();
  } else if (type == "cube") {
    *shape.mutable_mesh() = CubeMesh();
  } else if (type == "disk") {
    rule = NormalRule::kTransformed;
    *shape.mutable_mesh() = assembly_.Made(DiskMesh(DiskUv::kMitsuba), e.where);
    Warn(e.where, "disk", "disk shapes are meshed as fans of " + std::to_string(kDiskSegments) + " triangles");
  } else if (type == "cylinder") {
    rule = NormalRule::kTransformed;
    const Vec3d p0 = p.Point("p0", {0, 0, 0}), p1 = p.Point("p1", {0, 0, 1});
    const double radius = p.Float("radius", 1);
    if (!(radius > 0 && radius < 1e30)) Fail(p.WhereIs("radius"), "cylinder radius must be positive");
    const Vec3d axis = p1 - p0;
    const auto frame = Matrix4::LookAt(p0, p1, std::abs(axis.y) < 0.9 * Length(axis) ? Vec3d{0, 1, 0} : Vec3d{1, 0, 0});
    if (!frame) Fail(e.where, "cylinder: p0 and p1 must differ");
    *shape.mutable_mesh() = assembly_.Made(CylinderMesh(360), e.where);
    cylinder_frame = *frame * Matrix4::Scale({radius, radius, Length(axis)});
    Warn(e.where, "cylinder",
         "cylinder shapes are meshed as tubes of " + std::to_string(kCylinderSegments) + " quads");
  } else if (type == "bsplinecurve" || type == "linearcurve") {
    rule = NormalRule::kSphere;
    const auto file = folder_.Resolve(p.String("filename", ""), e.file, p.WhereIs("filename"));
    *shape.mutable_curves() =
        MitsubaCurves(ReadTextFile(file, e.where), type == "linearcurve", {folder_.Relative(file), 0});
  } else {
    static const std::vector<std::string> kKnown = {"obj",      "ply",       "serialized",   "sphere",
                                                    "rectangle", "cube",     "disk",         "cylinder",
                                                    "instance",  "shapegroup", "bsplinecurve", "linearcurve"};
    if (!p.Objects("sensor").empty())
      Fail(e.where, "shape type '" + type + "' is not supported, and a sensor sits on it" + DidYouMean(type, kKnown));
    Warn(e.where, "shape:" + type, "shape type '" + type + "' is not supported: ignored" + DidYouMean(type, kKnown));
    return;
  }
  const Matrix4 to_world = p.Transform("to_world") * cylinder_frame;
  if (shape.has_curves()) {
    // Mitsuba's radii are world lengths, which to_world leaves alone; yarf
    // scales a curve's radii with its placement, as a sphere's.
    const double scale = std::cbrt(std::abs(to_world.Determinant3()));
    v1::Curves& curves = *shape.mutable_curves();
    if (scale > 0 && std::isfinite(scale))
      for (int i = 3; i < curves.points_size(); i += 4) curves.set_points(i, float(curves.points(i) / scale));
  }
  const bool flip = p.Boolean("flip_normals", false);

  // The media either side: the interior against the normal.
  for (const char* side : {"interior", "exterior"}) {
    const XmlElement* medium = p.Object(side);
    if (!medium) continue;
    if (medium->tag != "medium")
      Fail(medium->where, p.Describe() + ": '" + side + "' must be a <medium>, not <" + medium->tag + ">");
    const std::string name = Medium(*medium);
    std::string(side) == "interior" ? shape.set_interior(name) : shape.set_exterior(name);
  }
  // An irradiance meter measures on its shape, which the camera then names.
  const auto sensors = p.Objects("sensor");
  const XmlElement* meter = nullptr;
  if (!sensors.empty()) {
    if (sensors.size() > 1) Fail(sensors[1]->where, "a shape holds one sensor");
    if (sensors.front()->Get("type") != "irradiancemeter")
      Fail(sensors.front()->where, "sensor '" + sensors.front()->Get("type") +
                                       "' inside a shape: only an irradiancemeter can be declared there");
    if (!group.empty())
      Fail(sensors.front()->where,
           "an irradiancemeter on a shape of a shapegroup is not supported: place it in the world");
    if (assembly_.HasCamera())
      Warn(sensors.front()->where, "second-sensor", "a second <sensor> ignored: yarf renders the first");
    else
      meter = sensors.front();
  }
  const auto emitters = p.Objects("emitter");
  const auto bsdfs = p.Objects("bsdf");
  if (bsdfs.size() > 1) Fail(bsdfs[1]->where, "a shape takes one BSDF");
  std::string material = bsdfs.empty() ? assembly_.DefaultMaterial() : Material(*bsdfs.front());
  if (material.empty()) {
    // A null BSDF: a medium boundary or an emitter that does not scatter;
    // a surface that is neither is invisible, and left out.
    const bool emits = std::any_of(emitters.begin(), emitters.end(),
                                   [](const XmlElement* emitter) { return emitter->Get("type") == "area"; });
    if (shape.interior().empty() && shape.exterior().empty() && !emits && !meter) {
      p.WarnUnused();
      return;
    }
    material = assembly_.NullMaterial();
  }
  shape.set_material(material);
  if (const std::string alpha = bsdfs.empty() ? "" : MaskAlpha(*bsdfs.front()); !alpha.empty()) {
    if (shape.has_sphere() || shape.has_curves())
      Warn(bsdfs.front()->where, "mask-" + type,
           "mask opacity on a " + type + " is not supported: the shape is opaque");
    else
      shape.set_alpha(alpha);
  }
  for (const XmlElement* emitter : emitters) {
    if (emitter->Get("type") != "area") {
      Warn(emitter->where, "shape-emitter:" + emitter->Get("type"),
           "emitter '" + emitter->Get("type") + "' attached to a shape ignored (only area emitters can be)");
      continue;
    }
    attached_emitters_.insert(emitter);
    if (shape.has_curves()) {
      Warn(emitter->where, "curve-emitter", "area emitters on curves are not supported: emission ignored");
      continue;
    }
    if (shape.has_emitter()) Fail(emitter->where, "a shape takes one area emitter");
    *shape.mutable_emitter() = AreaEmitter(*emitter);
  }
  if (meter) {
    shape.set_name(assembly_.UnusedShapeName(shape.name().empty() ? "irradiancemeter's shape" : shape.name()));
    IrradianceMeter(*meter, shape.name());
  }
  p.WarnUnused();
  assembly_.AddShape(std::move(shape), to_world, flip, rule, e.where, group);
}

void MitsubaImporter::ShapeGroup(const XmlElement& e) {
  const std::string& id = e.Required("id");
  if (!groups_made_.insert(id).second) return;
  assembly_.Group(id);
  for (const XmlElement& child : e.children) {
    if (child.tag == "shape" || child.tag == "ref") {
      const XmlElement& shape = child.tag == "ref" ? Lookup(child.Required("id"), child.where) : child;
      if (shape.tag != "shape") Fail(child.where, "a shapegroup holds shapes only");
      Shape(shape, id);
    } else {
      Warn(child.where, "shapegroup:" + child.tag, "<" + child.tag + "> inside a shapegroup ignored");
    }
  }
}

void MitsubaImporter::Instance(XmlPlugin& p) {
  const auto groups = p.Objects("shape");
  if (groups.size() != 1 || groups.front()->Get("type") != "shapegroup")
    Fail(p.where(), "an instance needs exactly one shapegroup (a <ref> to it)");
  ShapeGroup(*groups.front());
  const Matrix4 to_world = p.Transform("to_world");
  p.WarnUnused();
  assembly_.AddInstance(groups.front()->Get("id"), to_world, p.where());
}

}  // namespace yarf::importers
