#include "service/listen_port.h"

#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <string>

#include "yarf/error.h"

namespace yarf {
namespace {

struct AddressListDeleter {
  void operator()(addrinfo* list) const { freeaddrinfo(list); }
};

}  // namespace

FileDescriptor::~FileDescriptor() {
  if (fd_ >= 0) close(fd_);
}

FileDescriptor& FileDescriptor::operator=(FileDescriptor&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) close(fd_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

std::optional<std::pair<std::string, std::string>> SplitHostPort(std::string_view address) {
  if (address.starts_with("unix:") || address.starts_with("unix-abstract:")) return std::nullopt;
  if (address.starts_with("dns:")) address.remove_prefix(4);
  while (address.starts_with("/")) address.remove_prefix(1);  // dns:///host:port
  const size_t colon = address.rfind(':');
  if (colon == std::string_view::npos || colon + 1 == address.size()) return std::nullopt;
  std::string host(address.substr(0, colon));
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  return std::pair{std::move(host), std::string(address.substr(colon + 1))};
}

using AddressList = std::unique_ptr<addrinfo, AddressListDeleter>;

// The addresses to bind for `host` (all of this machine's when empty) and
// `port`; null when the name does not resolve.
static AddressList Resolve(const std::string& host, const std::string& port) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  addrinfo* found = nullptr;
  if (getaddrinfo(host.empty() ? nullptr : host.c_str(), port.c_str(), &hints, &found) != 0) return nullptr;
  return AddressList(found);
}

void CheckPortFree(std::string_view listen) {
  const auto split = SplitHostPort(listen);
  if (!split) return;  // a unix socket, or an address gRPC itself refuses
  const auto& [host, port] = *split;
  if (port.find_first_not_of('0') == std::string::npos) return;  // any free port
  const AddressList addresses = Resolve(host, port);
  const addrinfo* found = addresses.get();
  for (const addrinfo* address = found; address; address = address->ai_next) {
    const FileDescriptor probe(socket(address->ai_family, address->ai_socktype | SOCK_CLOEXEC, address->ai_protocol));
    if (probe.get() < 0) continue;
    // As gRPC binds: SO_REUSEADDR (a port left in TIME_WAIT is free), no
    // SO_REUSEPORT (a port another socket listens on is not).
    const int on = 1;
    setsockopt(probe.get(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    if (bind(probe.get(), address->ai_addr, address->ai_addrlen) != 0 && errno == EADDRINUSE)
      throw Error("cannot listen on " + std::string(listen) + ": " + std::strerror(EADDRINUSE) +
                  " (another process holds it; yarfd does not share a port)");
  }
}

FileDescriptor ListenTcp(std::string_view address, int& port) {
  const auto split = SplitHostPort(address);
  if (!split) throw Error("cannot listen on '" + std::string(address) + "': not HOST:PORT");
  const AddressList addresses = Resolve(split->first, split->second);
  if (!addresses) throw Error("cannot listen on " + std::string(address) + ": the host does not resolve");
  int error = 0;
  for (const addrinfo* candidate = addresses.get(); candidate; candidate = candidate->ai_next) {
    FileDescriptor listener(
        socket(candidate->ai_family, candidate->ai_socktype | SOCK_CLOEXEC, candidate->ai_protocol));
    if (listener.get() < 0) continue;
    const int on = 1;
    setsockopt(listener.get(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    if (bind(listener.get(), candidate->ai_addr, candidate->ai_addrlen) != 0 || listen(listener.get(), 16) != 0) {
      error = errno;
      continue;
    }
    sockaddr_storage bound{};
    socklen_t size = sizeof bound;
    getsockname(listener.get(), reinterpret_cast<sockaddr*>(&bound), &size);
    port = ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<const sockaddr_in6&>(bound).sin6_port
                                             : reinterpret_cast<const sockaddr_in&>(bound).sin_port);
    return listener;
  }
  throw Error("cannot listen on " + std::string(address) + ": " + std::strerror(error ? error : EADDRNOTAVAIL));
}

}  // namespace yarf
