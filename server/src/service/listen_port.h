// yarfd's listening port, checked before anything else starts.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace yarf {

// An open file descriptor, closed with this.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd = -1) : fd_(fd) {}
  ~FileDescriptor();
  FileDescriptor(FileDescriptor&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  FileDescriptor& operator=(FileDescriptor&& other) noexcept;
  int get() const { return fd_; }

 private:
  int fd_;
};

// "HOST:PORT", "[V6]:PORT" or "dns:///HOST:PORT" as host and port (the
// brackets gone); nullopt for a unix socket or a form without a port.
std::optional<std::pair<std::string, std::string>> SplitHostPort(std::string_view address);

// Throws Error naming `listen` (as --listen takes it) when another process
// holds that TCP address. yarfd never shares a port (no SO_REUSEPORT): two
// servers on one port would split its clients between them. Checked before
// plugins load and the state folder is locked, so that a second server
// stops at once; gRPC's own bind, without SO_REUSEPORT, still refuses a
// port taken in between. A unix socket or port 0 is not checked.
void CheckPortFree(std::string_view listen);

// A TCP socket listening on `address` (HOST:PORT; port 0 for any free
// one, then read back into `port`), for a server of yarfd's own besides
// gRPC. Throws Error naming the address when it cannot listen there.
FileDescriptor ListenTcp(std::string_view address, int& port);

}  // namespace yarf
