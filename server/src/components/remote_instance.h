// Remote<I>: a C++ interface implemented by calling a component that lives
// in another process (COM's containment). The kernel cannot tell it from
// an in-process plugin. RemoteInstance is what every Remote<I> shares: the
// channel, the instance made at the component, deadlines, retries on a
// restarted component, and errors that name the component and the call.
#pragma once

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "yarf/error.h"
#include "yarf/v1/component.pb.h"

namespace yarf {

template <typename I>
class Remote;

// The calls in flight of one job's remote components, so that cancelling
// the job ends them at once instead of at their deadlines.
class RemoteCalls {
 public:
  // Cancels every call in flight and every later one.
  void Cancel();
  bool cancelled() const;

 private:
  friend class RemoteInstance;
  void Begin(grpc::ClientContext* context);
  void End(grpc::ClientContext* context);

  mutable std::mutex mutex_;
  std::vector<grpc::ClientContext*> in_flight_;
  bool cancelled_ = false;
};

struct RemoteOptions {
  // Deadline of each call.
  std::chrono::milliseconds deadline{std::chrono::seconds(60)};
  // Times a call is retried, after making the instance anew, when the
  // component went away (UNAVAILABLE) or forgot the instance (NOT_FOUND).
  uint32_t retries = 0;
  // Where calls are tracked for cancellation; none when null.
  std::shared_ptr<RemoteCalls> calls;
};

// A channel to a component process: "host:port" or "unix:/path".
std::shared_ptr<grpc::Channel> ComponentChannel(const std::string& address);

// Whether an interface id is one of this server's IDL version ("yarf.v1.").
bool SpeaksOurIdl(const std::string& interface_id);

class RemoteInstance {
 public:
  // Makes an instance of `class_name` at `address`, after checking with
  // Describe that the class serves `interface_id`; released at destruction.
  RemoteInstance(std::string address, std::string class_name, v1::Properties properties,
                 std::string interface_id, RemoteOptions options);
  // Uses an instance someone else made (e.g. a client serving one function
  // as handle 0); not released, not re-made.
  RemoteInstance(std::string address, uint64_t handle, std::string interface_id, RemoteOptions options);
  ~RemoteInstance();
  RemoteInstance(const RemoteInstance&) = delete;
  RemoteInstance& operator=(const RemoteInstance&) = delete;

  const std::shared_ptr<grpc::Channel>& channel() const { return channel_; }
  const std::string& address() const { return address_; }
  const std::string& class_name() const { return class_name_; }
  // The instance's handle at the component (a retry may make it anew).
  uint64_t handle() const {
    std::lock_guard lock(mutex_);
    return handle_;
  }

  // Runs one call: `call(context, handle)` with the deadline set. A
  // failure throws Error naming the component and "Interface.method";
  // when the component went away and retries are left, the instance is
  // made anew (waiting for the component to come back) and the call
  // repeated.
  void Call(const char* method,
            const std::function<grpc::Status(grpc::ClientContext&, uint64_t handle)>& call) const;

  // An Error about a reply of `method` that the caller found wrong.
  Error BadReply(const char* method, const std::string& what) const;

  // Reply checks: `array` must be FLOAT32 (UINT32) [rows, trailing...];
  // its values are copied to `out`. Floats must be finite.
  void CopyFloats(const char* method, const char* field, const v1::Array& array, size_t rows,
                  std::initializer_list<uint32_t> trailing, std::span<float> out) const;
  void CopyUints(const char* method, const char* field, const v1::Array& array, size_t rows,
                 std::span<uint32_t> out) const;
  // Reply check: no value of `field` (a radiance, a pdf, a coefficient) is
  // negative.
  void RequireNonNegative(const char* method, const char* field, std::span<const float> values) const;

  // "component 'py_lambertian' at unix:/tmp/c.sock".
  std::string Name() const;

 private:
  uint64_t Make() const;
  void CheckShape(const char* method, const char* field, const v1::Array& array, v1::Array::DType dtype,
                  size_t rows, std::initializer_list<uint32_t> trailing) const;

  const std::string address_;
  const std::string class_name_;
  const v1::Properties properties_;
  const std::string interface_id_;
  const RemoteOptions options_;
  const bool owned_;
  std::shared_ptr<grpc::Channel> channel_;
  mutable std::mutex mutex_;
  mutable uint64_t handle_ = 0;
};

// A dense batch for a request (little-endian hosts: the bytes are the values).
void SetFloats(v1::Array* array, std::span<const float> values, std::initializer_list<uint32_t> shape);

}  // namespace yarf
