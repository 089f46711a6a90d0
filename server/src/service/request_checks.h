// The checks every field of a request gets before the request is looked
// at as a scene: numbers finite and of sane magnitude, text valid UTF-8 of
// bounded length, the whole message of bounded size. One rule for every
// field, walked by reflection, so a field added to the IDL is covered
// without a line here.
#pragma once

#include <google/protobuf/message.h>

#include <cstddef>
#include <string>
#include <string_view>

namespace yarf {

struct RequestLimits {
  // Largest |x| of any float or double: positions, radii, intensities.
  // Squares and products of two such numbers stay finite in float.
  static constexpr double kMaxMagnitude = 1e12;
  // Longest text field (names, classes, addresses, files, keys)...
  static constexpr size_t kMaxNameBytes = 1 << 10;
  // ...except a string property value, which may hold e.g. an expression.
  static constexpr size_t kMaxTextValueBytes = 64 << 10;
  // Largest serialized Submit: bigger meshes travel as assets (AssetService).
  static constexpr size_t kMaxSubmitBytes = 64 << 20;
  // Longest error kept and shown for a job.
  static constexpr size_t kMaxErrorBytes = 64 << 10;
};

// Throws Error naming the field path (e.g. "scene.camera.origin.x") of the
// first number or text that breaks the limits above.
void CheckRequestFields(const google::protobuf::Message& message);

// Whether `text` is well-formed UTF-8 (no overlongs, surrogates or bytes
// past U+10FFFF).
bool IsValidUtf8(std::string_view text);

// `text` made fit to show and store: ill-formed UTF-8 replaced by U+FFFD
// and cut, at a character boundary, to at most `max_bytes` (with "…").
std::string SafeText(std::string_view text, size_t max_bytes);

}  // namespace yarf
