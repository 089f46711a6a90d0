// Who is calling, for the services' permission checks: the user and role
// of the caller's bearer token. A server on loopback without tokens
// treats every caller as the local admin.
#pragma once

#include <google/protobuf/message.h>
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
Caller CallerOf(const grpc::ServerContextBase& context);

// Whether `caller` may see and act on a job (or an instance) of `owner`.
bool MayActOn(const Caller& caller, const std::string& owner);

// Whether `request` sets a field `address` or `*_address` anywhere in it:
// yarfd would dial that address, as itself, and hand the process data.
bool NamesAddress(const google::protobuf::Message& request);

// PERMISSION_DENIED unless `caller` is an admin or `request` names no
// component process (NamesAddress).
grpc::Status MayNameAddresses(const Caller& caller, const google::protobuf::Message& request);

}  // namespace yarf
