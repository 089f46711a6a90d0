// Classes made in component processes: announced by Registry.Register
// (a lease the component renews) or by the server's command line (for
// good). The server makes their instances at the component's address.
#pragma once

#include <chrono>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "components/registry.h"

namespace yarf {

// A class name another origin holds already.
class ClassConflict : public Error {
 public:
  using Error::Error;
};

class RemoteClasses {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::chrono::seconds kDefaultLease{30}, kMaxLease{3600};

  explicit RemoteClasses(const Registry& local) : local_(local) {}

  // Asks the component at `address` for its classes (Registry.ListClasses
  // there), checks their interfaces are of this server's IDL version and
  // their names free, and makes them here until the lease runs out (a
  // zero lease: for good). Registering again renews. Throws Error when
  // the component cannot be reached or speaks another IDL version,
  // ClassConflict when a name is taken.
  std::vector<ComponentInfo> Register(const std::string& address, std::chrono::seconds lease);
  // False when the address is not registered.
  bool Unregister(const std::string& address);

  // Where `class_name` is made, while its lease lasts.
  std::optional<std::string> AddressOf(const std::string& class_name) const;
  std::vector<ComponentInfo> Classes() const;

 private:
  struct Endpoint {
    std::vector<ComponentInfo> classes;
    std::optional<Clock::time_point> expires;
  };
  // Drops endpoints whose lease ran out; called with the lock held.
  void DropExpired() const;

  const Registry& local_;
  mutable std::mutex mutex_;
  mutable std::map<std::string, Endpoint> endpoints_;
};

}  // namespace yarf
