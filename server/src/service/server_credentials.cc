#include "service/server_credentials.h"

#include <arpa/inet.h>
#include <grpcpp/security/server_credentials.h>

#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "service/token_auth.h"
#include "yarf/error.h"

namespace yarf {
namespace {

std::string ReadPem(const std::filesystem::path& path, const std::string& flag) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error("cannot read " + flag + " " + path.string());
  std::ostringstream text;
  text << file.rdbuf();
  if (text.str().find("-----BEGIN ") == std::string::npos)
    throw Error(flag + " " + path.string() + " is not a PEM file");
  return text.str();
}

std::string Join(const std::vector<std::string>& parts) {
  std::string joined;
  for (const auto& part : parts) joined += (joined.empty() ? "" : " ") + part;
  return joined;
}

}  // namespace

bool IsLoopback(std::string_view listen) {
  // unix-abstract: is not: an abstract socket has no file permissions, so
  // any process in the network namespace may connect to it.
  if (listen.starts_with("unix:")) return true;
  // HOST:PORT, [IPV6]:PORT, or HOST alone.
  std::string host(listen.substr(0, listen.rfind(':')));
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  if (host == "localhost") return true;
  unsigned char v4[4];
  if (inet_pton(AF_INET, host.c_str(), v4) == 1) return v4[0] == 127;
  in6_addr v6;
  return inet_pton(AF_INET6, host.c_str(), &v6) == 1 && std::memcmp(&v6, &in6addr_loopback, sizeof v6) == 0;
}

std::shared_ptr<grpc::ServerCredentials> ListenCredentials(const ServerOptions& options) {
  if (options.tls_cert.empty() != options.tls_key.empty())
    throw Error("--tls-cert and --tls-key go together: add " +
                std::string(options.tls_cert.empty() ? "--tls-cert FILE" : "--tls-key FILE"));
  const bool tls = !options.tls_cert.empty();
  const bool tokens = !options.tokens_file.empty();
  // A token sent in plaintext can be read, and reused, by anyone on the way.
  if (tokens && !tls) throw Error("--tokens needs TLS: add --tls-cert FILE --tls-key FILE");
  if (!IsLoopback(options.listen) && !(tls && tokens)) {
    std::vector<std::string> missing;
    if (!tls) missing.push_back("--tls-cert FILE --tls-key FILE");
    if (!tokens) missing.push_back("--tokens FILE");
    const std::string reach = options.listen.starts_with("unix-abstract:")
                                  ? " is an abstract socket, which any process in this network namespace can"
                                    " connect to (it has no file permissions)"
                                  : " is reachable from other machines";
    throw Error("--listen " + options.listen + reach + ", which needs TLS and bearer tokens: add " + Join(missing) +
                " (or listen on 127.0.0.1 or unix:PATH)");
  }
  if (!tls) return grpc::InsecureServerCredentials();
  grpc::SslServerCredentialsOptions ssl;
  ssl.pem_key_cert_pairs.push_back({ReadPem(options.tls_key, "--tls-key"), ReadPem(options.tls_cert, "--tls-cert")});
  auto credentials = grpc::SslServerCredentials(ssl);
  if (tokens)
    credentials->SetAuthMetadataProcessor(std::make_shared<TokenAuthProcessor>(ReadTokenFile(options.tokens_file)));
  return credentials;
}

}  // namespace yarf
