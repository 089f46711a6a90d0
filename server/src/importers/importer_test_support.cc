#include "importers/importer_test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace yarf::importers::testing {

std::filesystem::path TestScene(const std::string& name) {
  return std::filesystem::path(YARF_IMPORT_TEST_SCENES) / name;
}

ImportResult Import(const std::string& name, const ImportOptions& options) {
  return ImportSceneFile(TestScene(name), options);
}

std::string ImportErrorOf(const std::string& name) {
  try {
    Import(name);
  } catch (const ImportError& error) {
    return error.what();
  }
  return "";
}

const v1::SceneShape& ShapeNamed(const v1::Scene& scene, const std::string& name) {
  for (const v1::SceneShape& shape : scene.shapes())
    if (shape.name() == name) return shape;
  throw std::runtime_error("no shape named " + name);
}

const v1::Material& MaterialNamed(const v1::Scene& scene, const std::string& name) {
  for (const v1::Material& material : scene.materials())
    if (material.name() == name) return material;
  throw std::runtime_error("no material named " + name);
}

const v1::Material& MaterialOf(const v1::Scene& scene, const v1::SceneShape& shape) {
  return MaterialNamed(scene, shape.material());
}

const v1::Light& LightNamed(const v1::Scene& scene, const std::string& name) {
  for (const v1::Light& light : scene.lights())
    if (light.name() == name) return light;
  throw std::runtime_error("no light named " + name);
}

Matrix4 ToMatrix(const v1::Transform& transform) {
  if (transform.m_size() != 16) return Matrix4();
  std::array<double, 16> m;
  for (int i = 0; i < 16; ++i) m[i] = transform.m(i);
  return Matrix4(m);
}

bool IsRotation(const Matrix4& m) {
  const Vec3d x = m.Vector({1, 0, 0}), y = m.Vector({0, 1, 0}), z = m.Vector({0, 0, 1});
  const auto near = [](double a, double b) { return std::abs(a - b) < 1e-9; };
  return near(Dot(x, x), 1) && near(Dot(y, y), 1) && near(Dot(z, z), 1) && near(Dot(x, y), 0) &&
         near(Dot(y, z), 0) && near(Dot(z, x), 0) && near(m.Determinant3(), 1);
}

bool Warns(const ImportResult& result, const std::string& fragment) {
  for (const std::string& warning : result.warnings)
    if (warning.find(fragment) != std::string::npos) return true;
  return false;
}

namespace {
const v1::Property& Get(const v1::Properties& p, const std::string& name) {
  const auto it = p.values().find(name);
  if (it == p.values().end()) throw std::runtime_error("no property " + name);
  return it->second;
}
}  // namespace

double FloatProperty(const v1::Properties& p, const std::string& name) { return Get(p, name).float_value(); }
int64_t IntProperty(const v1::Properties& p, const std::string& name) { return Get(p, name).int_value(); }
std::string StringProperty(const v1::Properties& p, const std::string& name) {
  return Get(p, name).string_value();
}
Vec3d RgbProperty(const v1::Properties& p, const std::string& name) {
  const v1::Rgb& c = Get(p, name).rgb_value();
  return {c.r(), c.g(), c.b()};
}

}  // namespace yarf::importers::testing
