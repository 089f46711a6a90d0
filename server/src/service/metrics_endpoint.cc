#include "service/metrics_endpoint.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>

#include <string>

namespace yarf {
namespace {

void SendAll(int connection, std::string_view data) {
  while (!data.empty()) {
    const ssize_t sent = send(connection, data.data(), data.size(), MSG_NOSIGNAL);
    if (sent <= 0) return;
    data.remove_prefix(size_t(sent));
  }
}

std::string Response(std::string_view status, std::string_view type, std::string_view body) {
  return "HTTP/1.1 " + std::string(status) + "\r\nContent-Type: " + std::string(type) +
         "\r\nContent-Length: " + std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + std::string(body);
}

}  // namespace

MetricsEndpoint::MetricsEndpoint(std::string_view address, std::function<std::string()> exposition)
    : listener_(ListenTcp(address, port_)),
      exposition_(std::move(exposition)),
      thread_([this](const std::stop_token& stop) { Serve(stop); }) {}

void MetricsEndpoint::Serve(const std::stop_token& stop) {
  while (!stop.stop_requested()) {
    pollfd waiting{listener_.get(), POLLIN, 0};
    if (poll(&waiting, 1, 200) <= 0) continue;
    const FileDescriptor connection(accept4(listener_.get(), nullptr, nullptr, SOCK_CLOEXEC));
    if (connection.get() < 0) continue;
    const timeval limit{2, 0};
    setsockopt(connection.get(), SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
    setsockopt(connection.get(), SOL_SOCKET, SO_SNDTIMEO, &limit, sizeof limit);
    Answer(connection.get());
  }
}

void MetricsEndpoint::Answer(int connection) const {
  // The request line and headers; the body of a GET is empty.
  std::string request;
  char buffer[1024];
  while (request.find("\r\n\r\n") == std::string::npos && request.size() < 8192) {
    const ssize_t got = recv(connection, buffer, sizeof buffer, 0);
    if (got <= 0) return;
    request.append(buffer, size_t(got));
  }
  const std::string_view line = std::string_view(request).substr(0, request.find("\r\n"));
  if (line.starts_with("GET /metrics ") || line.starts_with("GET /metrics?")) {
    SendAll(connection, Response("200 OK", "text/plain; version=0.0.4; charset=utf-8", exposition_()));
  } else if (line.starts_with("GET ")) {
    SendAll(connection, Response("404 Not Found", "text/plain", "yarfd serves its metrics at /metrics\n"));
  } else {
    SendAll(connection, Response("405 Method Not Allowed", "text/plain", "GET /metrics only\n"));
  }
}

}  // namespace yarf
