// mesh_attribute — a value stored with a mesh, per vertex or per face
// (Mitsuba's `mesh_attribute`)
//
// Reads the attribute `name` of the shape a point lies on: a vertex
// attribute ("vertex_color", "vertex_NAME") interpolated over its
// triangle, a face attribute ("face_color", "face_NAME") its triangle's
// value, scaled by `scale`. Points on shapes without the attribute, and
// points whose caller gives no location (a remote lookup), read 0.
//
// Parameters: MeshAttribute::Parameters() below.
//
// Channels: 3 (a one-channel attribute in all three). Mean: 0.5 in each
// channel, a stand-in: the texture alone cannot know the meshes it is
// used on.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "texture_rows.h"
#include "yarf/plugin.h"

namespace {

class MeshAttribute final : public yarf::Texture {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::String("name").Required().Doc("the attribute: \"vertex_…\" or \"face_…\""),
        P::Float("scale").Default(1).Doc("multiplies the attribute"),
    };
  }

  explicit MeshAttribute(const yarf::Properties& props)
      : name_(props.String("name", "")), scale_(float(props.Float("scale", 1.0))) {
    if (!name_.starts_with("vertex_") && !name_.starts_with("face_"))
      throw yarf::Error("property 'name' must start with 'vertex_' or 'face_', got '" + name_ + "'");
    if (!std::isfinite(scale_)) throw yarf::Error("property 'scale' must be finite");
  }

  uint32_t Channels() const override { return 3; }

  void Evaluate(const yarf::SurfacePoints& at, std::span<float> value) const override {
    yarf::textures::CheckShapes(at, value, 3);
    const size_t n = at.Count();
    if (at.attributes == nullptr || at.location.size() != n) {
      std::fill(value.begin(), value.end(), 0.0f);
      return;
    }
    at.attributes->Attribute(name_, at.location, value);
    for (float& v : value) v *= scale_;
  }

  std::vector<float> Mean() const override { return {0.5f, 0.5f, 0.5f}; }
  bool ReadsFootprints() const override { return false; }

 private:
  std::string name_;
  float scale_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<MeshAttribute>(registrar, "mesh_attribute", "1.0.0",
                                "a mesh's per-vertex or per-face attribute (Mitsuba mesh_attribute)");
}
