// The credentials of yarfd's listening port: TLS with bearer tokens
// anywhere, plaintext without them on loopback only.
#pragma once

#include <grpcpp/security/server_credentials.h>

#include <memory>
#include <string_view>

#include "service/server_options.h"

namespace yarf {

// Whether `listen` (as --listen takes it) is reachable from this machine
// only: 127.0.0.0/8, ::1, localhost or a unix socket with a path. Any
// other form, unix-abstract: included, counts as reachable from elsewhere.
bool IsLoopback(std::string_view listen);

// TLS from --tls-cert/--tls-key, with --tokens checked on every call; or
// plaintext. Throws Error saying what to add when the address is not
// loopback and TLS or tokens are missing, when tokens come without TLS, or
// when a file cannot be read or holds a malformed line.
std::shared_ptr<grpc::ServerCredentials> ListenCredentials(const ServerOptions& options);

}  // namespace yarf
