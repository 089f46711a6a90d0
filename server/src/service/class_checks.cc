#include "service/class_checks.h"

#include <algorithm>
#include <string>

#include "components/parameter_checks.h"
#include "yarf/error.h"

namespace yarf {
namespace {

namespace pb = google::protobuf;

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

void Check(const pb::Message& message, const std::string& path, const std::vector<ComponentInfo>& known) {
  const pb::Reflection& reflection = *message.GetReflection();
  if (NamesAClass(*message.GetDescriptor())) {
    const std::string class_name = reflection.GetString(message, message.GetDescriptor()->FindFieldByName("class_name"));
    const std::string address = reflection.GetString(message, message.GetDescriptor()->FindFieldByName("address"));
    // An empty class is the slot's default; a class at an address is that process's to know.
    if (class_name.empty() || !address.empty()) return;
    const auto info = std::find_if(known.begin(), known.end(),
                                   [&](const ComponentInfo& k) { return k.class_name == class_name; });
    if (info != known.end()) {
      const auto* properties = message.GetDescriptor()->FindFieldByName("properties");
      CheckProperties(*info, static_cast<const v1::Properties&>(reflection.GetMessage(message, properties)),
                      path + ".properties");
      return;
    }
    std::vector<std::string> names;
    for (const ComponentInfo& k : known) names.push_back(k.class_name);
    const std::string nearest = DidYouMean(class_name, names);
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

void CheckComponents(const v1::SubmitRequest& request, const std::vector<ComponentInfo>& known) {
  Check(request.scene(), "scene", known);
  Check(request.options(), "options", known);
}

}  // namespace yarf
