// The arbitrary output variables the `aov` transport renders, by name:
// what RenderOptions.aovs may ask for beside a job's image.
#pragma once

#include <array>
#include <string>
#include <string_view>

namespace yarf {

inline constexpr std::array<std::string_view, 8> kAovNames = {
    "albedo", "sh_normal", "geo_normal", "depth", "position", "uv", "shape_index", "material_index"};

// The names, comma-separated, for messages.
inline std::string AovNameList() {
  std::string list;
  for (std::string_view name : kAovNames) {
    if (!list.empty()) list += ", ";
    list += name;
  }
  return list;
}

}  // namespace yarf
