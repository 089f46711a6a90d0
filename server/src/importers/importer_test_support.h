// Helpers of the importer tests: the test scenes and lookups in the
// Scenes they become.
#pragma once

#include <filesystem>
#include <string>

#include "importers/import.h"
#include "importers/matrix.h"

namespace yarf::importers::testing {

// tests/scenes/import/<name>
std::filesystem::path TestScene(const std::string& name);
ImportResult Import(const std::string& name, const ImportOptions& options = {});
// The message of the ImportError importing `name` raises ("" if none).
std::string ImportErrorOf(const std::string& name);

const v1::SceneShape& ShapeNamed(const v1::Scene& scene, const std::string& name);
const v1::Material& MaterialNamed(const v1::Scene& scene, const std::string& name);
const v1::Material& MaterialOf(const v1::Scene& scene, const v1::SceneShape& shape);
const v1::Light& LightNamed(const v1::Scene& scene, const std::string& name);
// Identity when the transform is absent.
Matrix4 ToMatrix(const v1::Transform& transform);
// Orthonormal columns and determinant +1, to 1e-9.
bool IsRotation(const Matrix4& m);
// True when a warning contains `fragment`.
bool Warns(const ImportResult& result, const std::string& fragment);

double FloatProperty(const v1::Properties& p, const std::string& name);
int64_t IntProperty(const v1::Properties& p, const std::string& name);
std::string StringProperty(const v1::Properties& p, const std::string& name);
Vec3d RgbProperty(const v1::Properties& p, const std::string& name);

}  // namespace yarf::importers::testing
