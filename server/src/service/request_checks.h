// The checks a Submit gets before its job is stored, in one place for
// yarfd and for the farm's coordinator (which asks `yarfd --check-requests`):
// first every field (numbers finite and of sane magnitude, text valid UTF-8
// of bounded length, the whole message of bounded size; one rule for every
// field, walked by reflection, so a field added to the IDL is covered
// without a line here), then the options and the scene.
#pragma once

#include <google/protobuf/message.h>

#include <cstddef>
#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

#include "components/scene_builder.h"
#include "yarf/component.h"
#include "yarf/v1/render.pb.h"

namespace yarf {

struct SubmitLimits {
  static constexpr uint32_t kDefaultSpp = 16;
  static constexpr uint32_t kMaxSpp = 1u << 20;
  static constexpr uint32_t kMaxComponentRetries = 100;
  static constexpr double kMaxComponentTimeout = 24 * 3600;
  static constexpr uint32_t kDefaultPriority = 50;
  static constexpr uint32_t kMaxPriority = 100;
  static constexpr uint32_t kMaxRetries = 10;
};

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

// The request as its job will run, its defaults filled in; throws Error
// for what is refused. With `assets`, every mesh asset the scene names
// must be one of them.
v1::SubmitRequest AcceptSubmit(const v1::SubmitRequest& request, const AssetSource* assets);

// `yarfd --check-requests`: answers each length-prefixed SubmitRequest
// read from `in` with a length-prefixed SubmitCheck on `out`, until `in`
// ends; returns the process's exit status. The classes in `known` tell
// how each job may be divided (SubmitCheck.splits); a class not among
// them is not refused, as it may be registered where the job runs.
int ServeRequestChecks(std::istream& in, std::ostream& out, const std::vector<ComponentInfo>& known);

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
