#include "service/access.h"

#include <grpcpp/security/auth_context.h>

namespace yarf {
namespace {

std::string Property(const grpc::AuthContext& context, const char* name) {
  const auto values = context.FindPropertyValues(name);
  return values.empty() ? std::string() : std::string(values.front().data(), values.front().size());
}

}  // namespace

std::string_view RoleName(Role role) { return role == Role::kAdmin ? "admin" : "submit"; }

Caller CallerOf(const grpc::ServerContext& context) {
  const auto auth = context.auth_context();
  const std::string user = auth ? Property(*auth, kUserProperty) : std::string();
  if (user.empty()) return {"local", Role::kAdmin};
  return {user, Property(*auth, kRoleProperty) == RoleName(Role::kAdmin) ? Role::kAdmin : Role::kSubmit};
}

bool MayActOn(const Caller& caller, const std::string& owner) {
  return caller.role == Role::kAdmin || caller.user == owner;
}

}  // namespace yarf
