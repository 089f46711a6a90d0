#include "service/server_metrics.h"

#include <chrono>
#include <cstdio>

namespace yarf {
namespace {

const std::vector<double> kCallSeconds = {0.001, 0.005, 0.01, 0.05, 0.1, 0.5, 1, 5, 30, 300};
const std::vector<double> kQueueSeconds = {0.01, 0.1, 1, 10, 60, 600, 3600, 86400};

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", value);
  return text;
}

const char* CodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::OK: return "OK";
    case grpc::CANCELLED: return "CANCELLED";
    case grpc::UNKNOWN: return "UNKNOWN";
    case grpc::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
    case grpc::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
    case grpc::NOT_FOUND: return "NOT_FOUND";
    case grpc::ALREADY_EXISTS: return "ALREADY_EXISTS";
    case grpc::PERMISSION_DENIED: return "PERMISSION_DENIED";
    case grpc::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
    case grpc::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
    case grpc::ABORTED: return "ABORTED";
    case grpc::OUT_OF_RANGE: return "OUT_OF_RANGE";
    case grpc::UNIMPLEMENTED: return "UNIMPLEMENTED";
    case grpc::INTERNAL: return "INTERNAL";
    case grpc::UNAVAILABLE: return "UNAVAILABLE";
    case grpc::DATA_LOSS: return "DATA_LOSS";
    case grpc::UNAUTHENTICATED: return "UNAUTHENTICATED";
    default: return "OTHER";
  }
}

// Label values here are method names and fixed words; escaped all the same.
std::string LabelValue(std::string_view text) {
  std::string out;
  for (const char c : text) {
    if (c == '\\' || c == '"') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out;
}

void Header(std::string& out, std::string_view name, std::string_view type, std::string_view help) {
  out.append("# HELP ").append(name).append(" ").append(help).append("\n");
  out.append("# TYPE ").append(name).append(" ").append(type).append("\n");
}

// Times one call: made by gRPC as the call starts, ended by it after the
// call has ended.
class CallTimerInterceptor final : public grpc::experimental::Interceptor {
 public:
  CallTimerInterceptor(ServerMetrics& metrics, std::string method)
      : metrics_(metrics), method_(std::move(method)), start_(std::chrono::steady_clock::now()) {}

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    using grpc::experimental::InterceptionHookPoints;
    if (methods->QueryInterceptionHookPoint(InterceptionHookPoints::PRE_SEND_STATUS))
      metrics_.RecordCall(method_, methods->GetSendStatus().error_code(),
                          std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
    methods->Proceed();
  }

 private:
  ServerMetrics& metrics_;
  const std::string method_;
  const std::chrono::steady_clock::time_point start_;
};

class CallTimerFactory final : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  explicit CallTimerFactory(ServerMetrics& metrics) : metrics_(metrics) {}
  grpc::experimental::Interceptor* CreateServerInterceptor(grpc::experimental::ServerRpcInfo* info) override {
    // gRPC takes ownership of the interceptor and deletes it when the call ends.
    return std::make_unique<CallTimerInterceptor>(metrics_, info->method() ? info->method() : "").release();
  }

 private:
  ServerMetrics& metrics_;
};

}  // namespace

Histogram::Histogram(std::vector<double> bounds) : bounds_(std::move(bounds)), counts_(bounds_.size() + 1, 0) {}

void Histogram::Observe(double value) {
  size_t bucket = 0;
  while (bucket < bounds_.size() && value > bounds_[bucket]) ++bucket;
  ++counts_[bucket];
  sum_ += value;
  ++count_;
}

void Histogram::Write(std::string& out, std::string_view name, std::string_view labels) const {
  const std::string prefix = labels.empty() ? "" : std::string(labels) + ",";
  uint64_t cumulative = 0;
  for (size_t i = 0; i <= bounds_.size(); ++i) {
    cumulative += counts_[i];
    const std::string le = i < bounds_.size() ? Number(bounds_[i]) : "+Inf";
    out.append(name).append("_bucket{").append(prefix).append("le=\"").append(le).append("\"} ");
    out.append(std::to_string(cumulative)).append("\n");
  }
  const std::string braces = labels.empty() ? "" : "{" + std::string(labels) + "}";
  out.append(name).append("_sum").append(braces).append(" ").append(Number(sum_)).append("\n");
  out.append(name).append("_count").append(braces).append(" ").append(std::to_string(count_)).append("\n");
}

ServerMetrics::ServerMetrics() : queue_wait_(kQueueSeconds) {}

void ServerMetrics::OnJobEvent(const JobEvent& event) {
  std::lock_guard lock(mutex_);
  ++events_[std::string(EventName(event.kind))];
  if (event.kind == JobEventKind::kStarted) queue_wait_.Observe(event.queue_seconds);
}

void ServerMetrics::OnProgress(uint64_t pixel_samples, uint64_t rays) {
  pixel_samples_ += pixel_samples;
  rays_ += rays;
}

void ServerMetrics::RecordCall(std::string_view method, grpc::StatusCode code, double seconds) {
  std::lock_guard lock(mutex_);
  auto key = std::make_pair(std::string(method), std::string(CodeName(code)));
  auto it = calls_.find(key);
  if (it == calls_.end()) it = calls_.emplace(std::move(key), Histogram(kCallSeconds)).first;
  it->second.Observe(seconds);
}

std::string ServerMetrics::Exposition(const std::map<std::string, uint64_t>& jobs_by_state) const {
  std::string out;
  Header(out, "yarf_jobs", "gauge", "Jobs the server holds, by state.");
  for (const auto& [state, count] : jobs_by_state)
    out.append("yarf_jobs{state=\"").append(LabelValue(state)).append("\"} ").append(std::to_string(count)) += "\n";
  Header(out, "yarf_pixel_samples_total", "counter",
         "Pixel samples rendered by jobs (samples per pixel times pixels); rate() gives samples per second.");
  out.append("yarf_pixel_samples_total ").append(std::to_string(pixel_samples_.load())) += "\n";
  Header(out, "yarf_rays_total", "counter",
         "Closest-hit and shadow rays traced by jobs; rate() gives rays per second.");
  out.append("yarf_rays_total ").append(std::to_string(rays_.load())) += "\n";
  std::lock_guard lock(mutex_);
  Header(out, "yarf_job_events_total", "counter", "Job events (as the job log tells them), by event.");
  for (const auto& [event, count] : events_)
    out.append("yarf_job_events_total{event=\"").append(event).append("\"} ").append(std::to_string(count)) += "\n";
  Header(out, "yarf_job_queue_wait_seconds", "histogram", "How long jobs waited in the queue before a run started.");
  queue_wait_.Write(out, "yarf_job_queue_wait_seconds", "");
  Header(out, "yarf_rpc_duration_seconds", "histogram",
         "How long calls took, by method and status code (for a stream, how long it was open).");
  for (const auto& [key, histogram] : calls_)
    histogram.Write(out, "yarf_rpc_duration_seconds",
                    "method=\"" + LabelValue(key.first) + "\",code=\"" + key.second + "\"");
  return out;
}

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> ServerMetrics::CallTimer() {
  return std::make_unique<CallTimerFactory>(*this);
}

}  // namespace yarf
