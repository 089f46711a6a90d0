// A minimal HTTP server for Prometheus to scrape: GET /metrics answers the
// exposition text, anything else 404. One connection at a time on a thread
// of its own (a scraper calls every few seconds); the request is read for
// at most two seconds, so a stalled client cannot hold it.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <thread>

#include "service/listen_port.h"

namespace yarf {

class MetricsEndpoint {
 public:
  // Listens on `address` (HOST:PORT, as --metrics takes it) and answers
  // with `exposition()`, called on the endpoint's thread. Throws Error
  // naming the address when it cannot listen.
  MetricsEndpoint(std::string_view address, std::function<std::string()> exposition);
  // Stops serving within a fraction of a second.
  ~MetricsEndpoint() = default;
  MetricsEndpoint(const MetricsEndpoint&) = delete;
  MetricsEndpoint& operator=(const MetricsEndpoint&) = delete;

  int port() const { return port_; }

 private:
  void Serve(const std::stop_token& stop);
  void Answer(int connection) const;

  int port_ = 0;
  FileDescriptor listener_;
  const std::function<std::string()> exposition_;
  // Last: stopped and joined first, while the members above still exist.
  std::jthread thread_;
};

}  // namespace yarf
