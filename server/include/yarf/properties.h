// Properties: the typed map that configures a component (proto Properties).
// It remembers which keys were read so that a key no class understood is
// reported instead of ignored.
#pragma once

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "yarf/error.h"
#include "yarf/vecmath.h"

namespace yarf {

struct Rgb {
  Vec3 value;
};
struct Reference {
  std::string name;
};
class Texture;
class SurfaceModel;

class Properties {
 public:
  // A Reference to a scene's texture reaches the component resolved, as
  // the texture itself; a file the server resolved (confined to the
  // scene's folder or the asset store) as a path, which no request can
  // set directly.
  using Value = std::variant<double, int64_t, bool, std::string, Vec3, Rgb, Transform, Reference,
                             std::shared_ptr<const Texture>, std::shared_ptr<const SurfaceModel>,
                             std::filesystem::path, std::vector<float>>;

  void Set(const std::string& key, Value value) { values_[key] = std::move(value); }
  // Sets a key the scene left out to the class's declared default: a key
  // the class may leave unread (it reads it only in some modes).
  void SetDefault(const std::string& key, Value value) {
    values_[key] = std::move(value);
    read_.insert(key);
  }
  bool Has(const std::string& key) const { return values_.count(key) != 0; }

  double Float(const std::string& key, double fallback) const {
    return Has(key) ? Float(key) : fallback;
  }
  double Float(const std::string& key) const {
    const Value& v = Find(key);
    if (auto* i = std::get_if<int64_t>(&v)) return double(*i);
    return Get<double>(key, v, "float");
  }
  int64_t Int(const std::string& key, int64_t fallback) const {
    return Has(key) ? Get<int64_t>(key, Find(key), "int") : fallback;
  }
  // An int that must lie in [lo, hi]: counts that size what a job
  // allocates (photons, records) are bounded here, not by the memory left.
  int64_t Int(const std::string& key, int64_t fallback, int64_t lo, int64_t hi) const {
    const int64_t value = Int(key, fallback);
    if (value < lo || value > hi)
      throw Error("property '" + key + "' must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                  "], got " + std::to_string(value));
    return value;
  }
  bool Bool(const std::string& key, bool fallback) const {
    return Has(key) ? Get<bool>(key, Find(key), "bool") : fallback;
  }
  std::string String(const std::string& key, const std::string& fallback) const {
    return Has(key) ? Get<std::string>(key, Find(key), "string") : fallback;
  }
  Vec3 Vector(const std::string& key, Vec3 fallback) const {
    return Has(key) ? Get<Vec3>(key, Find(key), "vec3") : fallback;
  }
  // An RGB value; a plain number f (float or int) is accepted as (f, f, f).
  Vec3 Color(const std::string& key, Vec3 fallback) const { return Has(key) ? Color(key) : fallback; }
  // A required RGB value.
  Vec3 Color(const std::string& key) const {
    const Value& v = Find(key);
    if (auto* f = std::get_if<double>(&v)) return Vec3(float(*f), float(*f), float(*f));
    if (auto* i = std::get_if<int64_t>(&v)) return Vec3(float(*i), float(*i), float(*i));
    return Get<Rgb>(key, v, "rgb").value;
  }
  // An RGB reflectance: every channel in [0, 1].
  Vec3 Reflectance(const std::string& key, Vec3 fallback) const {
    const Vec3 rgb = Color(key, fallback);
    for (int c = 0; c < 3; ++c)
      if (!(rgb[c] >= 0.0f && rgb[c] <= 1.0f))
        throw Error("property '" + key + "' must lie in [0, 1] in every channel");
    return rgb;
  }
  // The texture property `key` names; null when it is absent or holds a
  // plain value.
  std::shared_ptr<const Texture> TextureOf(const std::string& key) const {
    if (!Has(key)) return nullptr;
    if (auto* reference = std::get_if<Reference>(&values_.at(key)))
      throw Error("property '" + key + "' refers to '" + reference->name + "', which is not a texture of the scene");
    auto* texture = std::get_if<std::shared_ptr<const Texture>>(&values_.at(key));
    if (!texture) return nullptr;
    Find(key);
    return *texture;
  }
  // The material property `key` names (a wrapper's nested model), which
  // must be given and be a material of the scene defined before this one.
  std::shared_ptr<const SurfaceModel> SurfaceModelOf(const std::string& key) const {
    if (!Has(key)) throw Error("property '" + key + "' (a material of the scene) is missing");
    if (auto* reference = std::get_if<Reference>(&values_.at(key)))
      throw Error("property '" + key + "' refers to '" + reference->name +
                  "', which is not a material defined before this one");
    return Get<std::shared_ptr<const SurfaceModel>>(key, Find(key), "material");
  }
  Transform Matrix(const std::string& key, const Transform& fallback) const {
    return Has(key) ? Get<Transform>(key, Find(key), "transform") : fallback;
  }
  // A required list of numbers (proto FloatArray).
  const std::vector<float>& FloatArray(const std::string& key) const {
    return Get<std::vector<float>>(key, Find(key), "float array");
  }
  // Whether `key` holds a list of numbers (without reading it).
  bool HasFloatArray(const std::string& key) const {
    return Has(key) && std::holds_alternative<std::vector<float>>(values_.at(key));
  }

  // The file property `key` names, as the server resolved it: a readable
  // local path. A plain string is refused: only the server names files.
  std::filesystem::path ResolvedFile(const std::string& key) const {
    return Get<std::filesystem::path>(key, Find(key), "file (resolved by the server)");
  }

  // The folder where components may keep files between jobs (caches): the
  // host gives each user one of their own. Empty: no files at all.
  void SetFileFolder(std::filesystem::path folder) { file_folder_ = std::move(folder); }
  // The file a string property names, inside the file folder; empty when
  // the key is absent or "". The value is a plain file name (letters,
  // digits, '.', '_', '-'; not starting with '.'), never a path: a job
  // cannot read or replace a file outside its user's folder.
  std::filesystem::path File(const std::string& key) const {
    const std::string name = String(key, "");
    if (name.empty()) return {};
    const auto plain = [](char c) {
      return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
             c == '-';
    };
    if (name.size() > 255 || name[0] == '.' || !std::all_of(name.begin(), name.end(), plain))
      throw Error("property '" + key + "' must be a plain file name (letters, digits, '.', '_', '-'; not a path): " +
                  "files live in your folder on the server");
    if (file_folder_.empty()) throw Error("property '" + key + "': this server keeps no files for components here");
    return file_folder_ / name;
  }

  // Keys set but never read: a misspelt or unsupported parameter.
  std::vector<std::string> Unread() const {
    std::vector<std::string> out;
    for (const auto& [key, value] : values_)
      if (!read_.count(key)) out.push_back(key);
    return out;
  }
  const std::map<std::string, Value>& values() const { return values_; }

 private:
  const Value& Find(const std::string& key) const {
    auto it = values_.find(key);
    if (it == values_.end()) throw Error("missing property '" + key + "'");
    read_.insert(key);
    return it->second;
  }
  template <typename T>
  static const T& Get(const std::string& key, const Value& v, const char* type) {
    if (auto* p = std::get_if<T>(&v)) return *p;
    throw Error("property '" + key + "' must be of type " + type);
  }

  std::map<std::string, Value> values_;
  mutable std::set<std::string> read_;
  std::filesystem::path file_folder_;
};

}  // namespace yarf
