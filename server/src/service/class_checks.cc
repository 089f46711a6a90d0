#include "service/class_checks.h"

#include <algorithm>

#include "yarf/error.h"

namespace yarf {
namespace {

namespace pb = google::protobuf;

// Insertions, deletions, substitutions and swaps of neighbours ("bpdt"
// for "bdpt" is one), each counting one.
size_t EditDistance(std::string_view a, std::string_view b) {
  const size_t columns = b.size() + 1;
  std::vector<size_t> d((a.size() + 1) * columns);
  const auto at = [&](size_t i, size_t j) -> size_t& { return d[i * columns + j]; };
  for (size_t i = 0; i <= a.size(); ++i) at(i, 0) = i;
  for (size_t j = 0; j <= b.size(); ++j) at(0, j) = j;
  for (size_t i = 1; i <= a.size(); ++i)
    for (size_t j = 1; j <= b.size(); ++j) {
      at(i, j) = std::min({at(i - 1, j) + 1, at(i, j - 1) + 1, at(i - 1, j - 1) + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        at(i, j) = std::min(at(i, j), at(i - 2, j - 2) + 1);
    }
  return at(a.size(), b.size());
}

// Where a message is in the request, with its name when it has one.
std::string Place(const std::string& path, const pb::Message& message) {
  const pb::FieldDescriptor* name = message.GetDescriptor()->FindFieldByName("name");
  if (!name || name->type() != pb::FieldDescriptor::TYPE_STRING || name->is_repeated()) return path;
  const std::string value = message.GetReflection()->GetString(message, name);
  return value.empty() ? path : path + " ('" + value + "')";
}

bool NamesAClass(const pb::Descriptor& type) {
  return type.full_name() == v1::ComponentSpec::descriptor()->full_name() ||
         type.full_name() == v1::Material::descriptor()->full_name();
}

void Check(const pb::Message& message, const std::string& path, const std::vector<std::string>& known) {
  const pb::Reflection& reflection = *message.GetReflection();
  if (NamesAClass(*message.GetDescriptor())) {
    const std::string class_name = reflection.GetString(message, message.GetDescriptor()->FindFieldByName("class_name"));
    const std::string address = reflection.GetString(message, message.GetDescriptor()->FindFieldByName("address"));
    // An empty class is the slot's default; a class at an address is that process's to know.
    if (class_name.empty() || !address.empty()) return;
    if (std::find(known.begin(), known.end(), class_name) != known.end()) return;
    const std::string nearest = DidYouMean(class_name, known);
    throw Error(path + ".class_name: unknown component class '" + class_name + "'" +
                (nearest.empty() ? "" : "; did you mean '" + nearest + "'?") +
                " (`yarf classes` lists the classes this server can make)");
  }
  std::vector<const pb::FieldDescriptor*> fields;
  reflection.ListFields(message, &fields);
  for (const pb::FieldDescriptor* field : fields) {
    if (field->cpp_type() != pb::FieldDescriptor::CPPTYPE_MESSAGE) continue;
    const std::string field_path = path.empty() ? field->name() : path + "." + field->name();
    if (!field->is_repeated()) {
      Check(reflection.GetMessage(message, field), field_path, known);
      continue;
    }
    const int count = reflection.FieldSize(message, field);
    for (int i = 0; i < count; ++i) {
      const pb::Message& element = reflection.GetRepeatedMessage(message, field, i);
      Check(element, Place(field_path + "[" + std::to_string(i) + "]", element), known);
    }
  }
}

}  // namespace

std::string DidYouMean(std::string_view name, const std::vector<std::string>& candidates) {
  // Near enough: a few letters wrong, fewer for short names.
  const size_t most = std::max<size_t>(1, std::min<size_t>(3, name.size() / 3));
  std::string nearest;
  size_t best = most + 1;
  for (const std::string& candidate : candidates) {
    const size_t distance = EditDistance(name, candidate);
    if (distance < best) {
      best = distance;
      nearest = candidate;
    }
  }
  return nearest;
}

void CheckClassesKnown(const v1::SubmitRequest& request, const std::vector<std::string>& known) {
  Check(request.scene(), "scene", known);
  Check(request.options(), "options", known);
}

}  // namespace yarf
