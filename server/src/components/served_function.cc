#include "components/served_function.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <mutex>
#include <vector>

#include "components/array_codec.h"
#include "yarf/v1/math.grpc.pb.h"

namespace yarf {
namespace {

constexpr int kMaxMessageBytes = 256 << 20;
// Largest batch a component may ask for, in values (as yarfd's own services).
constexpr uint64_t kMaxValues = uint64_t(1) << 26;

// "host" of "host:port", "[::1]:port", "dns:///host:port", "ipv4:host:port".
std::string HostOf(std::string address) {
  for (const char* scheme : {"dns:///", "ipv4:", "ipv6:"})
    if (address.rfind(scheme, 0) == 0) address = address.substr(std::string(scheme).size());
  if (!address.empty() && address[0] == '[') return address.substr(1, address.find(']') - 1);
  const size_t colon = address.rfind(':');
  return colon == std::string::npos ? address : address.substr(0, colon);
}

bool IsLoopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

// The address of this machine a datagram to `host` would leave from (no
// packet is sent: connect on UDP only picks the route).
std::string LocalAddressTowards(const std::string& host) {
  addrinfo hints{};
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  if (getaddrinfo(host.c_str(), "9", &hints, &found) != 0 || !found)
    throw Error("cannot resolve the component's host '" + host + "' to serve it the function");
  std::unique_ptr<addrinfo, decltype(&freeaddrinfo)> owned(found, freeaddrinfo);
  const int socket_fd = socket(found->ai_family, SOCK_DGRAM, 0);
  if (socket_fd < 0) throw Error("no socket to find the route to '" + host + "'");
  sockaddr_storage local{};
  socklen_t length = sizeof local;
  const bool routed = connect(socket_fd, found->ai_addr, found->ai_addrlen) == 0 &&
                      getsockname(socket_fd, reinterpret_cast<sockaddr*>(&local), &length) == 0;
  close(socket_fd);
  if (!routed) throw Error("no route to the component's host '" + host + "' to serve it the function");
  char text[INET6_ADDRSTRLEN] = {};
  if (local.ss_family == AF_INET6) {
    inet_ntop(AF_INET6, &reinterpret_cast<sockaddr_in6*>(&local)->sin6_addr, text, sizeof text);
    return "[" + std::string(text) + "]";
  }
  inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(&local)->sin_addr, text, sizeof text);
  return text;
}

}  // namespace

// yarf.v1.Function for the one function, as handle 0. Calls are taken one
// at a time: a Function's Evaluate is not promised to be reentrant.
class ServedFunction::Service final : public v1::Function::Service {
 public:
  explicit Service(Function& function) : function_(function) {}

  grpc::Status Signature(grpc::ServerContext*, const v1::FunctionSignatureRequest* request,
                         v1::FunctionSignature* reply) override {
    if (request->handle() != 0) return Unknown(request->handle());
    reply->set_input_dimensions(function_.InputDimensions());
    reply->set_output_dimensions(function_.OutputDimensions());
    return grpc::Status::OK;
  }

  grpc::Status Evaluate(grpc::ServerContext*, const v1::EvaluateRequest* request, v1::EvaluateReply* reply) override {
    return Answer(*request, *reply);
  }

  grpc::Status EvaluateStream(grpc::ServerContext*,
                              grpc::ServerReaderWriter<v1::EvaluateReply, v1::EvaluateRequest>* stream) override {
    v1::EvaluateRequest request;
    while (stream->Read(&request)) {
      v1::EvaluateReply reply;
      if (grpc::Status status = Answer(request, reply); !status.ok()) return status;
      if (!stream->Write(reply)) break;
    }
    return grpc::Status::OK;
  }

 private:
  static grpc::Status Unknown(uint64_t handle) {
    return {grpc::StatusCode::NOT_FOUND, "no function " + std::to_string(handle) + " (this endpoint serves one, as 0)"};
  }

  grpc::Status Answer(const v1::EvaluateRequest& request, v1::EvaluateReply& reply) {
    if (request.handle() != 0) return Unknown(request.handle());
    try {
      const uint32_t d = function_.InputDimensions(), k = function_.OutputDimensions();
      size_t n = 0;
      const std::vector<float> points = FloatsOf(request.points(), {d}, "points", n);
      if (uint64_t(n) * std::max(d, k) > kMaxValues)
        throw Error("batch of " + std::to_string(n) + " points exceeds " + std::to_string(kMaxValues) + " values");
      std::vector<float> values(n * k);
      {
        std::lock_guard lock(mutex_);
        function_.Evaluate(points, values);
      }
      *reply.mutable_values() = FloatArray(values, {uint32_t(n), k});
      reply.set_sequence(request.sequence());
      return grpc::Status::OK;
    } catch (const std::exception& e) {
      return {grpc::StatusCode::INVALID_ARGUMENT, std::string("Function: ") + e.what()};
    }
  }

  Function& function_;
  std::mutex mutex_;
};

ServedFunction::ServedFunction(Function& function, const std::string& component_address)
    : service_(std::make_unique<Service>(function)) {
  std::string listen, host;
  if (component_address.rfind("unix:", 0) == 0) {
    std::string pattern = (std::filesystem::temp_directory_path() / "yarf-function-XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw Error("cannot make a folder to serve the function in");
    folder_ = pattern;  // mode 0700: only this user reaches the socket
    listen = "unix:" + (folder_ / "f.sock").string();
  } else {
    const std::string component_host = HostOf(component_address);
    host = IsLoopback(component_host) ? (component_host == "::1" ? "[::1]" : "127.0.0.1")
                                      : LocalAddressTowards(component_host);
    listen = host + ":0";
  }
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(listen, grpc::InsecureServerCredentials(), host.empty() ? nullptr : &port);
  builder.SetMaxReceiveMessageSize(kMaxMessageBytes);
  builder.SetMaxSendMessageSize(kMaxMessageBytes);
  builder.RegisterService(service_.get());
  server_ = builder.BuildAndStart();
  if (!server_) {
    if (!folder_.empty()) std::filesystem::remove_all(folder_);
    throw Error("cannot listen on " + listen + " to serve the function");
  }
  address_ = host.empty() ? listen : host + ":" + std::to_string(port);
}

ServedFunction::~ServedFunction() {
  server_->Shutdown(std::chrono::system_clock::now());
  server_->Wait();
  std::error_code ignored;
  if (!folder_.empty()) std::filesystem::remove_all(folder_, ignored);
}

}  // namespace yarf
