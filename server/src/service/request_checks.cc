#include "service/request_checks.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/stubs/logging.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <istream>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "components/scene_builder.h"
#include "service/access.h"
#include "service/job_splits.h"
#include "yarf/aov.h"
#include "yarf/error.h"

namespace yarf {
namespace {

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;
using google::protobuf::Reflection;

// The length of the well-formed UTF-8 character at text[at], 0 if none.
size_t CharacterLength(std::string_view text, size_t at) {
  const auto byte = [&](size_t i) { return static_cast<unsigned char>(text[i]); };
  const unsigned char lead = byte(at);
  if (lead < 0x80) return 1;
  size_t length;
  uint32_t code, least;
  if ((lead & 0xE0) == 0xC0) length = 2, code = lead & 0x1F, least = 0x80;
  else if ((lead & 0xF0) == 0xE0) length = 3, code = lead & 0x0F, least = 0x800;
  else if ((lead & 0xF8) == 0xF0) length = 4, code = lead & 0x07, least = 0x10000;
  else return 0;
  if (at + length > text.size()) return 0;
  for (size_t i = 1; i < length; ++i) {
    if ((byte(at + i) & 0xC0) != 0x80) return 0;
    code = code << 6 | (byte(at + i) & 0x3F);
  }
  // Overlong forms, UTF-16 surrogates and code points past Unicode's end.
  if (code < least || (code >= 0xD800 && code <= 0xDFFF) || code > 0x10FFFF) return 0;
  return length;
}

std::string Join(const std::string& path, const FieldDescriptor& field) {
  return path.empty() ? field.name() : path + "." + field.name();
}

// A string property's value may be long; every other text is a name.
size_t TextLimit(const Message& message, const FieldDescriptor& field) {
  return message.GetDescriptor()->full_name() == "yarf.v1.Property" && field.name() == "string_value"
             ? RequestLimits::kMaxTextValueBytes
             : RequestLimits::kMaxNameBytes;
}

std::string Format(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", value);
  return text;
}

// `path` makes the field's name, only for an error: an inline mesh has
// millions of numbers.
template <typename Path>
void CheckNumber(double value, const Path& path) {
  if (!std::isfinite(value)) [[unlikely]]
    throw Error(path() + " is " + Format(value) + "; every number must be finite");
  if (std::abs(value) > RequestLimits::kMaxMagnitude) [[unlikely]]
    throw Error(path() + " is " + Format(value) + ", beyond the largest magnitude a scene may use (1e12)");
}

template <typename Path>
void CheckText(const std::string& text, size_t limit, const Path& path) {
  if (text.size() > limit)
    throw Error(path() + " is " + std::to_string(text.size()) + " bytes long, more than the " +
                std::to_string(limit) + " it may be");
  if (!IsValidUtf8(text)) throw Error(path() + " is not valid UTF-8");
}

void CheckFields(const Message& message, const std::string& path) {
  const Reflection& reflection = *message.GetReflection();
  std::vector<const FieldDescriptor*> fields;
  reflection.ListFields(message, &fields);
  for (const FieldDescriptor* field : fields) {
    const std::string where = Join(path, *field);
    const bool repeated = field->is_repeated();
    const int count = repeated ? reflection.FieldSize(message, field) : 1;
    for (int i = 0; i < count; ++i) {
      const auto at = [&] {
        if (!field->is_map()) return repeated ? where + "[" + std::to_string(i) + "]" : where;
        // A map entry is named by its key (a property's name).
        const Message& entry = reflection.GetRepeatedMessage(message, field, i);
        const FieldDescriptor* key = entry.GetDescriptor()->map_key();
        if (key->cpp_type() != FieldDescriptor::CPPTYPE_STRING) return where + "[" + std::to_string(i) + "]";
        return where + "['" + SafeText(entry.GetReflection()->GetString(entry, key), 64) + "']";
      };
      switch (field->cpp_type()) {
        case FieldDescriptor::CPPTYPE_DOUBLE:
          CheckNumber(repeated ? reflection.GetRepeatedDouble(message, field, i) : reflection.GetDouble(message, field),
                      at);
          break;
        case FieldDescriptor::CPPTYPE_FLOAT:
          CheckNumber(repeated ? reflection.GetRepeatedFloat(message, field, i) : reflection.GetFloat(message, field),
                      at);
          break;
        case FieldDescriptor::CPPTYPE_STRING:
          // Bytes (a mesh file's contents) are the parsers' to check.
          if (field->type() == FieldDescriptor::TYPE_STRING)
            CheckText(repeated ? reflection.GetRepeatedString(message, field, i) : reflection.GetString(message, field),
                      TextLimit(message, *field), at);
          break;
        case FieldDescriptor::CPPTYPE_MESSAGE:
          CheckFields(
              repeated ? reflection.GetRepeatedMessage(message, field, i) : reflection.GetMessage(message, field), at());
          break;
        default:
          break;  // integers, bools and enums: their fields' own ranges apply
      }
    }
  }
}

// A share of a job (first_sample, crop) within its samples and film; that
// its integrator can render one is CheckShare's part, with the classes.
void ValidateShare(const v1::SubmitRequest& request) {
  const v1::RenderOptions& options = request.options();
  if (options.first_sample() == 0 && !options.has_crop()) return;
  if (options.first_sample() >= options.spp())
    throw Error("first_sample " + std::to_string(options.first_sample()) + " must be below spp " +
                std::to_string(options.spp()));
  if (options.has_crop()) {
    const v1::PixelWindow& c = options.crop();
    const v1::Film& film = request.scene().film();
    if (!(c.x0() < c.x1() && c.y0() < c.y1() && c.x1() <= film.width() && c.y1() <= film.height()))
      throw Error("crop [" + std::to_string(c.x0()) + ", " + std::to_string(c.x1()) + ") x [" +
                  std::to_string(c.y0()) + ", " + std::to_string(c.y1()) + ") is not a window of the " +
                  std::to_string(film.width()) + "x" + std::to_string(film.height()) + " film");
  }
}

// Each arbitrary output variable known, and asked for once.
void ValidateAovs(const v1::RenderOptions& options) {
  std::vector<std::string_view> seen;
  for (const std::string& name : options.aovs()) {
    if (std::find(kAovNames.begin(), kAovNames.end(), name) == kAovNames.end())
      throw Error("aov '" + SafeText(name, 64) + "' is not one of " + AovNameList());
    if (std::find(seen.begin(), seen.end(), name) != seen.end()) throw Error("aov '" + name + "' is asked for twice");
    seen.push_back(name);
  }
}

}  // namespace

v1::SubmitRequest AcceptSubmit(const v1::SubmitRequest& request, const AssetSource* assets) {
  CheckRequestFields(request);
  v1::SubmitRequest accepted = request;
  uint32_t spp = request.options().spp();
  if (spp == 0) spp = SubmitLimits::kDefaultSpp;
  if (spp > SubmitLimits::kMaxSpp)
    throw Error("spp " + std::to_string(spp) + " is out of range (1 to " + std::to_string(SubmitLimits::kMaxSpp) +
                ")");
  accepted.mutable_options()->set_spp(spp);
  const double timeout = request.options().component_timeout_seconds();
  if (!(timeout >= 0 && timeout <= SubmitLimits::kMaxComponentTimeout))
    throw Error("component_timeout_seconds " + std::to_string(timeout) + " is out of range (0 to " +
                std::to_string(SubmitLimits::kMaxComponentTimeout) + ")");
  if (request.options().component_retries() > SubmitLimits::kMaxComponentRetries)
    throw Error("component_retries " + std::to_string(request.options().component_retries()) +
                " is out of range (0 to " + std::to_string(SubmitLimits::kMaxComponentRetries) + ")");
  if (request.priority() > SubmitLimits::kMaxPriority)
    throw Error("priority " + std::to_string(request.priority()) + " is out of range (1 to " +
                std::to_string(SubmitLimits::kMaxPriority) + "; 0 means " +
                std::to_string(SubmitLimits::kDefaultPriority) + ")");
  if (request.priority() == 0) accepted.set_priority(SubmitLimits::kDefaultPriority);
  if (request.max_retries() > SubmitLimits::kMaxRetries)
    throw Error("max_retries " + std::to_string(request.max_retries()) + " is out of range (0 to " +
                std::to_string(SubmitLimits::kMaxRetries) + ")");
  ValidateScene(accepted.scene(), assets);
  ValidateShare(accepted);
  ValidateAovs(accepted.options());
  return accepted;
}

int ServeRequestChecks(std::istream& in, std::ostream& out, const std::vector<ComponentInfo>& known) {
  static_assert(std::endian::native == std::endian::little, "lengths are little-endian");
  // A request that does not parse is answered in its SubmitCheck; the
  // library's log line about it would only be noise on stderr.
  google::protobuf::SetLogHandler(nullptr);
  for (;;) {
    uint32_t length = 0;
    if (!in.read(reinterpret_cast<char*>(&length), sizeof length)) return in.eof() && in.gcount() == 0 ? 0 : 1;
    v1::SubmitCheck check;
    if (length > RequestLimits::kMaxSubmitBytes) {
      in.ignore(length);
      check.set_error("the request takes " + std::to_string(length) + " bytes, more than the " +
                      std::to_string(RequestLimits::kMaxSubmitBytes) + " (64 MiB) a job may");
    } else {
      std::string bytes(length, '\0');
      if (!in.read(bytes.data(), length)) return 1;
      v1::SubmitRequest request;
      try {
        if (!request.ParseFromString(bytes)) throw Error("the request is not a SubmitRequest");
        check.set_names_address(NamesAddress(request));
        const v1::SubmitRequest accepted = AcceptSubmit(request, nullptr);
        *check.mutable_splits() = SplitsOf(accepted, known);
        CheckShare(accepted, check.splits());
        for (std::string& warning : SubmitWarnings(accepted, known)) check.add_warnings(std::move(warning));
        *check.mutable_accepted() = accepted;
      } catch (const Error& e) {
        check.set_error(SafeText(e.what(), RequestLimits::kMaxErrorBytes));
      }
    }
    const std::string reply = check.SerializeAsString();
    const uint32_t reply_length = uint32_t(reply.size());
    out.write(reinterpret_cast<const char*>(&reply_length), sizeof reply_length);
    out.write(reply.data(), std::streamsize(reply.size()));
    if (!out.flush()) return 1;
  }
}

void CheckRequestFields(const Message& message) {
  const size_t bytes = message.ByteSizeLong();
  if (bytes > RequestLimits::kMaxSubmitBytes)
    throw Error("the request takes " + std::to_string(bytes) + " bytes, more than the " +
                std::to_string(RequestLimits::kMaxSubmitBytes) +
                " (64 MiB) a job may; upload large meshes with AssetService and name them by hash");
  CheckFields(message, "");
}

bool IsValidUtf8(std::string_view text) {
  for (size_t at = 0; at < text.size();) {
    const size_t length = CharacterLength(text, at);
    if (length == 0) return false;
    at += length;
  }
  return true;
}

std::string SafeText(std::string_view text, size_t max_bytes) {
  constexpr std::string_view kReplacement = "\xEF\xBF\xBD";  // U+FFFD
  constexpr std::string_view kEllipsis = "\xE2\x80\xA6";     // U+2026
  std::string out;
  std::vector<size_t> boundaries;  // where each character of `out` starts
  for (size_t at = 0; at < text.size();) {
    const size_t length = CharacterLength(text, at);
    boundaries.push_back(out.size());
    out += length ? text.substr(at, length) : kReplacement;
    at += length ? length : 1;
  }
  if (out.size() <= max_bytes) return out;
  if (max_bytes < kEllipsis.size()) return {};
  // The longest run of whole characters that leaves room for the ellipsis.
  const auto cut = std::upper_bound(boundaries.begin(), boundaries.end(), max_bytes - kEllipsis.size());
  out.resize(*(cut - 1));
  return out += kEllipsis;
}

}  // namespace yarf
