#include "service/scene_summary.h"

#include <cctype>
#include <string>

namespace yarf {
namespace {

void CountShapes(const google::protobuf::RepeatedPtrField<v1::SceneShape>& shapes, v1::SceneSummary& summary) {
  summary.set_shapes(summary.shapes() + shapes.size());
  for (const v1::SceneShape& shape : shapes)
    if (shape.has_emitter()) summary.set_lights(summary.lights() + 1);
}

}  // namespace

v1::SceneSummary SummarizeScene(const v1::Scene& scene) {
  v1::SceneSummary summary;
  summary.set_width(scene.film().width());
  summary.set_height(scene.film().height());
  summary.set_lights(scene.lights_size());
  CountShapes(scene.shapes(), summary);
  // A group's shapes once each, however often it is placed.
  uint32_t instances = scene.instances_size();
  for (const v1::Group& group : scene.groups()) {
    CountShapes(group.shapes(), summary);
    instances += group.instances_size();
  }
  summary.set_instances(instances);
  summary.set_materials(scene.materials_size());
  summary.set_textures(scene.textures_size());
  summary.set_media(scene.media_size());
  std::string camera = v1::Camera::Model_Name(scene.camera().model());
  for (char& c : camera) c = char(std::tolower(static_cast<unsigned char>(c)));
  summary.set_camera(camera);
  return summary;
}

}  // namespace yarf
