// yarfd's Prometheus metrics: what jobs do (counted from their events and
// progress) and how long calls take, written in Prometheus' text format.
// Off unless --metrics asks for them (metrics_endpoint.h serves them).
#pragma once

#include <grpcpp/support/server_interceptor.h>
#include <grpcpp/support/status.h>

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "service/job_events.h"

namespace yarf {

// Cumulative buckets of observed values, as Prometheus histograms are.
class Histogram {
 public:
  explicit Histogram(std::vector<double> bounds);
  void Observe(double value);
  // The _bucket, _sum and _count lines of `name`, each with `labels`
  // (`key="value",...` or empty) besides `le`.
  void Write(std::string& out, std::string_view name, std::string_view labels) const;

 private:
  std::vector<double> bounds_;
  std::vector<uint64_t> counts_;  // per bound, then +Inf; not cumulative
  double sum_ = 0;
  uint64_t count_ = 0;
};

class ServerMetrics final : public JobObserver {
 public:
  ServerMetrics();

  void OnJobEvent(const JobEvent& event) override;
  void OnProgress(uint64_t pixel_samples, uint64_t rays) override;
  // A call of `method` (/package.Service/Method) that ended with `code`
  // after `seconds`; for a stream, how long it was open.
  void RecordCall(std::string_view method, grpc::StatusCode code, double seconds);

  // The whole exposition; `jobs_by_state` holds the number of jobs in each
  // state now (state name → count).
  std::string Exposition(const std::map<std::string, uint64_t>& jobs_by_state) const;

  // Times every call the server answers into RecordCall, for
  // ServerBuilder::experimental().SetInterceptorCreators.
  std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> CallTimer();

 private:
  std::atomic<uint64_t> pixel_samples_{0}, rays_{0};
  mutable std::mutex mutex_;
  std::map<std::string, uint64_t> events_;  // by event name
  Histogram queue_wait_;
  std::map<std::pair<std::string, std::string>, Histogram> calls_;  // by method and code
};

}  // namespace yarf
