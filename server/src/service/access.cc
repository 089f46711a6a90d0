#include "service/access.h"

#include <google/protobuf/descriptor.h>
#include <grpcpp/security/auth_context.h>

#include <vector>

namespace yarf {
namespace {

std::string Property(const grpc::AuthContext& context, const char* name) {
  const auto values = context.FindPropertyValues(name);
  return values.empty() ? std::string() : std::string(values.front().data(), values.front().size());
}

}  // namespace

// A Material's or a ComponentSpec's `address`, an integrand's `function_address`.
bool NamesAddress(const google::protobuf::Message& message) {
  const google::protobuf::Reflection& reflection = *message.GetReflection();
  std::vector<const google::protobuf::FieldDescriptor*> fields;
  reflection.ListFields(message, &fields);
  for (const google::protobuf::FieldDescriptor* field : fields) {
    const std::string& name = field->name();
    if (field->cpp_type() == google::protobuf::FieldDescriptor::CPPTYPE_STRING && !field->is_repeated() &&
        (name == "address" || name.ends_with("_address")) && !reflection.GetString(message, field).empty())
      return true;
    if (field->cpp_type() != google::protobuf::FieldDescriptor::CPPTYPE_MESSAGE) continue;
    if (field->is_repeated()) {
      for (int i = 0; i < reflection.FieldSize(message, field); ++i)
        if (NamesAddress(reflection.GetRepeatedMessage(message, field, i))) return true;
    } else if (NamesAddress(reflection.GetMessage(message, field))) {
      return true;
    }
  }
  return false;
}

std::string_view RoleName(Role role) { return role == Role::kAdmin ? "admin" : "submit"; }

Caller CallerOf(const grpc::ServerContextBase& context) {
  const auto auth = context.auth_context();
  const std::string user = auth ? Property(*auth, kUserProperty) : std::string();
  if (user.empty()) return {"local", Role::kAdmin};
  return {user, Property(*auth, kRoleProperty) == RoleName(Role::kAdmin) ? Role::kAdmin : Role::kSubmit};
}

bool MayActOn(const Caller& caller, const std::string& owner) {
  return caller.role == Role::kAdmin || caller.user == owner;
}

grpc::Status MayNameAddresses(const Caller& caller, const google::protobuf::Message& request) {
  // Other users' processes are reached through classes an admin registered.
  if (caller.role == Role::kAdmin || !NamesAddress(request)) return grpc::Status::OK;
  return {grpc::StatusCode::PERMISSION_DENIED,
          "naming a component process by address needs the admin role; use a class an admin registered"};
}

}  // namespace yarf
