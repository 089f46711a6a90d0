#include "components/remote_instance.h"

#include <cmath>
#include <cstring>
#include <thread>

#include "yarf/v1/component.grpc.pb.h"

namespace yarf {
namespace {

constexpr int kMaxMessageBytes = 256 << 20;
constexpr const char* kIdlPrefix = "yarf.v1.";
// How long a retry waits, at most, for a restarted component to answer.
constexpr auto kRestartWait = std::chrono::seconds(10);
// Cold calls (Describe, Create, Release) are small.
constexpr auto kColdDeadline = std::chrono::seconds(10);

std::unique_ptr<grpc::ClientContext> ContextWithin(std::chrono::milliseconds deadline) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + deadline);
  return context;
}

std::string StatusText(const grpc::Status& status) {
  static const char* const kNames[] = {"OK",        "CANCELLED",          "UNKNOWN",        "INVALID_ARGUMENT",
                                       "DEADLINE_EXCEEDED", "NOT_FOUND",   "ALREADY_EXISTS", "PERMISSION_DENIED",
                                       "RESOURCE_EXHAUSTED", "FAILED_PRECONDITION", "ABORTED", "OUT_OF_RANGE",
                                       "UNIMPLEMENTED", "INTERNAL", "UNAVAILABLE", "DATA_LOSS", "UNAUTHENTICATED"};
  const int code = status.error_code();
  const std::string name = code >= 0 && code <= 16 ? kNames[code] : std::to_string(code);
  return name + ": " + status.error_message();
}

// The component went away or was restarted without the instance.
bool ComponentLost(const grpc::Status& status) {
  return status.error_code() == grpc::StatusCode::UNAVAILABLE ||
         status.error_code() == grpc::StatusCode::NOT_FOUND;
}

// "yarf.v1.SurfaceModel" -> "SurfaceModel".
std::string ShortName(const std::string& interface_id) {
  const size_t dot = interface_id.rfind('.');
  return dot == std::string::npos ? interface_id : interface_id.substr(dot + 1);
}

}  // namespace

std::shared_ptr<grpc::Channel> ComponentChannel(const std::string& address) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(kMaxMessageBytes);
  args.SetMaxSendMessageSize(kMaxMessageBytes);
  // Each Remote instance its own connection: calls of several materials
  // run side by side instead of queueing on one.
  args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args);
}

void RemoteCalls::Cancel() {
  std::lock_guard lock(mutex_);
  cancelled_ = true;
  for (grpc::ClientContext* context : in_flight_) context->TryCancel();
}

bool RemoteCalls::cancelled() const {
  std::lock_guard lock(mutex_);
  return cancelled_;
}

void RemoteCalls::Begin(grpc::ClientContext* context) {
  std::lock_guard lock(mutex_);
  in_flight_.push_back(context);
  if (cancelled_) context->TryCancel();
}

void RemoteCalls::End(grpc::ClientContext* context) {
  std::lock_guard lock(mutex_);
  std::erase(in_flight_, context);
}

bool SpeaksOurIdl(const std::string& interface_id) { return interface_id.rfind(kIdlPrefix, 0) == 0; }

RemoteInstance::RemoteInstance(std::string address, std::string class_name, v1::Properties properties,
                               std::string interface_id, RemoteOptions options)
    : address_(std::move(address)), class_name_(std::move(class_name)), properties_(std::move(properties)),
      interface_id_(std::move(interface_id)), options_(options), owned_(true), channel_(ComponentChannel(address_)) {
  v1::DescribeRequest request;
  request.set_class_name(class_name_);
  v1::ComponentInfo info;
  const grpc::Status status =
      v1::Component::NewStub(channel_)->Describe(ContextWithin(kColdDeadline).get(), request, &info);
  if (!status.ok()) throw Error(Name() + ": Component.Describe failed: " + StatusText(status));
  bool serves = false;
  for (const std::string& id : info.interfaces()) {
    if (id == interface_id_) serves = true;
    if (!SpeaksOurIdl(id))
      throw Error(Name() + " serves " + id + ", an interface of another IDL version (this server speaks " +
                  kIdlPrefix + "*)");
  }
  if (!serves) throw Error(Name() + " does not serve " + interface_id_);
  handle_ = Make();
}

RemoteInstance::RemoteInstance(std::string address, uint64_t handle, std::string interface_id,
                               RemoteOptions options)
    : address_(std::move(address)), interface_id_(std::move(interface_id)), options_(options), owned_(false),
      channel_(ComponentChannel(address_)), handle_(handle) {}

RemoteInstance::~RemoteInstance() {
  if (!owned_) return;
  // Best effort: a component that is gone has nothing left to release.
  v1::ReleaseRequest request;
  request.set_handle(handle_);
  v1::ReleaseReply reply;
  v1::Factory::NewStub(channel_)->Release(ContextWithin(std::chrono::seconds(2)).get(), request, &reply);
}

std::string RemoteInstance::Name() const {
  if (class_name_.empty()) return "remote " + ShortName(interface_id_) + " " + std::to_string(handle_) + " at " + address_;
  return "component '" + class_name_ + "' at " + address_;
}

uint64_t RemoteInstance::Make() const {
  v1::CreateRequest request;
  request.set_class_name(class_name_);
  *request.mutable_properties() = properties_;
  v1::CreateReply reply;
  const grpc::Status status =
      v1::Factory::NewStub(channel_)->Create(ContextWithin(kColdDeadline).get(), request, &reply);
  if (!status.ok()) throw Error(Name() + ": Factory.Create failed: " + StatusText(status));
  if (reply.handle() == 0) throw Error(Name() + ": Factory.Create returned handle 0");
  return reply.handle();
}

void RemoteInstance::Call(const char* method,
                          const std::function<grpc::Status(grpc::ClientContext&, uint64_t)>& call) const {
  const std::string what = ShortName(interface_id_) + "." + method;
  for (uint32_t attempt = 0;; ++attempt) {
    uint64_t handle;
    {
      std::lock_guard lock(mutex_);
      handle = handle_;
    }
    const std::unique_ptr<grpc::ClientContext> context = ContextWithin(options_.deadline);
    if (options_.calls) options_.calls->Begin(context.get());
    const grpc::Status status = call(*context, handle);
    if (options_.calls) options_.calls->End(context.get());
    if (status.ok()) return;
    if (options_.calls && options_.calls->cancelled()) throw Error(Name() + ": " + what + " cancelled with the job");
    if (!owned_ || attempt >= options_.retries || !ComponentLost(status))
      throw Error(Name() + ": " + what + " failed: " + StatusText(status));
    // Make the instance anew once the component answers again; another
    // thread may have done it already.
    std::lock_guard lock(mutex_);
    if (handle_ != handle) continue;
    const auto give_up = std::chrono::steady_clock::now() + kRestartWait;
    for (;;) {
      try {
        handle_ = Make();
        break;
      } catch (const Error& e) {
        if (std::chrono::steady_clock::now() > give_up)
          throw Error(Name() + ": " + what + " failed: " + StatusText(status) + "; retrying: " + e.what());
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
      }
    }
  }
}

Error RemoteInstance::BadReply(const char* method, const std::string& what) const {
  return Error(Name() + ": " + ShortName(interface_id_) + "." + method + " returned " + what);
}

void RemoteInstance::CheckShape(const char* method, const char* field, const v1::Array& array,
                                v1::Array::DType dtype, size_t rows, std::initializer_list<uint32_t> trailing) const {
  size_t count = rows;
  bool ok = array.dtype() == dtype && array.shape_size() == int(trailing.size()) + 1 && array.shape(0) == rows;
  int axis = 1;
  for (uint32_t extent : trailing) {
    if (ok && array.shape(axis) != extent) ok = false;
    ++axis;
    count *= extent;
  }
  if (!ok || array.data().size() != count * 4) {
    std::string shape = "[";
    for (int i = 0; i < array.shape_size(); ++i) shape += (i ? ", " : "") + std::to_string(array.shape(i));
    std::string expected = "[" + std::to_string(rows);
    for (uint32_t extent : trailing) expected += ", " + std::to_string(extent);
    throw BadReply(method, std::string(field) + " of shape " + shape + "] and " +
                               std::to_string(array.data().size() / 4) + " values for " + std::to_string(rows) +
                               " queries (expected " + expected + "])");
  }
}

void RemoteInstance::CopyFloats(const char* method, const char* field, const v1::Array& array, size_t rows,
                                std::initializer_list<uint32_t> trailing, std::span<float> out) const {
  CheckShape(method, field, array, v1::Array::FLOAT32, rows, trailing);
  std::memcpy(out.data(), array.data().data(), array.data().size());
  const size_t n = array.data().size() / 4;
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(out[i]))
      throw BadReply(method, "a non-finite value (" + std::to_string(out[i]) + ") in " + field + " at query " +
                                 std::to_string(i / std::max<size_t>(1, n / std::max<size_t>(rows, 1))));
}

void RemoteInstance::RequireNonNegative(const char* method, const char* field, std::span<const float> values) const {
  for (size_t i = 0; i < values.size(); ++i)
    if (values[i] < 0)
      throw BadReply(method, "a negative " + std::string(field) + " (" + std::to_string(values[i]) + ") at value " +
                                 std::to_string(i));
}

void RemoteInstance::CopyUints(const char* method, const char* field, const v1::Array& array, size_t rows,
                               std::span<uint32_t> out) const {
  CheckShape(method, field, array, v1::Array::UINT32, rows, {});
  std::memcpy(out.data(), array.data().data(), array.data().size());
}

void SetFloats(v1::Array* array, std::span<const float> values, std::initializer_list<uint32_t> shape) {
  array->set_dtype(v1::Array::FLOAT32);
  for (uint32_t extent : shape) array->add_shape(extent);
  array->set_data(reinterpret_cast<const char*>(values.data()), values.size_bytes());
}

}  // namespace yarf
