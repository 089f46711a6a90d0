// Bearer tokens: the tokens file, and the check every call on a TLS port
// passes before a service sees it. A known token puts its user and role
// into the call's auth context, where CallerOf (access.h) reads them.
#pragma once

#include <grpcpp/security/auth_metadata_processor.h>

#include <filesystem>
#include <mutex>
#include <string>
#include <string_view>
#include <unordered_map>

#include "service/access.h"

namespace yarf {

// Token → who holds it.
using TokenTable = std::unordered_map<std::string, Caller>;

// Reads a tokens file: one `TOKEN USER ROLE` per line, ROLE submit or
// admin; `#` starts a comment. Throws Error naming the file and line of a
// malformed entry (without echoing the token), or when it holds no token.
TokenTable ReadTokenFile(const std::filesystem::path& path);

// Methods open to callers without a token: health checks (load balancers
// and LocalServer probe them) and reflection (names of services only).
bool IsOpenMethod(std::string_view method);

// Methods only an admin may call, because they change the server for
// every user: which plugins and component processes provide classes.
bool IsAdminMethod(std::string_view method);

// Checks `authorization: Bearer <token>`: missing or unknown → UNAUTHENTICATED;
// an admin-only method with a submit token → PERMISSION_DENIED.
//
// gRPC gives every call of a connection the connection's one auth context,
// so the first token binds the connection to its user and role; a call
// with another user's token on that connection is UNAUTHENTICATED.
class TokenAuthProcessor final : public grpc::AuthMetadataProcessor {
 public:
  explicit TokenAuthProcessor(TokenTable tokens);

  // A table lookup: cheap enough to run on the call's own thread.
  bool IsBlocking() const override { return false; }

  grpc::Status Process(const InputMetadata& auth_metadata, grpc::AuthContext* context,
                       OutputMetadata* consumed_auth_metadata, OutputMetadata* response_metadata) override;

 private:
  const TokenTable tokens_;
  // Makes binding a connection (read, then add properties) one step.
  std::mutex binding_;
};

}  // namespace yarf
