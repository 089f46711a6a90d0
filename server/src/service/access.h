// Who is calling, for the services' permission checks: the user and role
// of the caller's bearer token. A server on loopback without tokens
// treats every caller as the local admin.
#pragma once

#include <grpcpp/server_context.h>

#include <string>
#include <string_view>

namespace yarf {

// Names of the auth-context properties the token check (token_auth.h) sets.
inline constexpr char kUserProperty[] = "yarf.user";
inline constexpr char kRoleProperty[] = "yarf.role";

enum class Role {
  // Submits jobs and acts on its own.
  kSubmit,
  // Loads plugins, registers components, acts on anyone's jobs.
  kAdmin,
};

struct Caller {
  std::string user;
  Role role;
};

// "submit" or "admin", as the tokens file and the role property spell it.
std::string_view RoleName(Role role);

// The caller of this call: from the properties the token check put in the
// call's auth context, else the local admin.
Caller CallerOf(const grpc::ServerContext& context);

// Whether `caller` may see and act on a job submitted by `owner`.
bool MayActOn(const Caller& caller, const std::string& owner);

}  // namespace yarf
