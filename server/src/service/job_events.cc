#include "service/job_events.h"

#include <cstdio>

namespace yarf {
namespace {

// A JSON string: quotes, backslashes and control characters escaped (the
// text is UTF-8 already: errors are made safe before they are stored).
std::string Quoted(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escape[8];
      std::snprintf(escape, sizeof escape, "\\u%04x", static_cast<unsigned>(c));
      out += escape;
    } else {
      out += c;
    }
  }
  return out + '"';
}

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", value);
  return text;
}

}  // namespace

std::string_view EventName(JobEventKind kind) {
  switch (kind) {
    case JobEventKind::kSubmitted: return "submitted";
    case JobEventKind::kStarted: return "started";
    case JobEventKind::kCheckpoint: return "checkpoint";
    case JobEventKind::kRequeued: return "requeued";
    case JobEventKind::kFinished: return "finished";
    case JobEventKind::kFailed: return "failed";
    case JobEventKind::kCancelled: return "cancelled";
  }
  return "unknown";
}

std::vector<std::pair<std::string_view, JobEventValue>> JobEventFields(const JobEvent& event) {
  std::vector<std::pair<std::string_view, JobEventValue>> fields = {
      {"event", std::string(EventName(event.kind))},
      {"job", event.job},
      {"owner", event.owner},
      {"attempt", uint64_t(event.attempt)},
      {"spp", uint64_t(event.spp_done)},
      {"spp_total", uint64_t(event.spp_total)},
      {"seconds", event.seconds},
      {"rays", event.rays},
  };
  if (event.kind == JobEventKind::kStarted) fields.emplace_back("queue_seconds", event.queue_seconds);
  if (!event.error.empty()) fields.emplace_back("error", event.error);
  return fields;
}

std::string FormatKeyValue(const JobEvent& event) {
  std::string line;
  for (const auto& [key, value] : JobEventFields(event)) {
    if (!line.empty()) line += ' ';
    line += key;
    line += '=';
    if (const auto* text = std::get_if<std::string>(&value)) {
      const bool plain = !text->empty() && text->find_first_of(" \"=\\\t\n\r") == std::string::npos;
      line += plain ? *text : Quoted(*text);
    } else if (const auto* count = std::get_if<uint64_t>(&value)) {
      line += std::to_string(*count);
    } else {
      line += Number(std::get<double>(value));
    }
  }
  return line;
}

std::string FormatJson(const JobEvent& event) {
  std::string line = "{";
  for (const auto& [key, value] : JobEventFields(event)) {
    if (line.size() > 1) line += ',';
    line += Quoted(key);
    line += ':';
    if (const auto* text = std::get_if<std::string>(&value))
      line += Quoted(*text);
    else if (const auto* count = std::get_if<uint64_t>(&value))
      line += std::to_string(*count);
    else
      line += Number(std::get<double>(value));
  }
  return line + '}';
}

void JobLog::OnJobEvent(const JobEvent& event) {
  const std::string line = json_ ? FormatJson(event) : FormatKeyValue(event);
  std::lock_guard lock(mutex_);
  out_ << line << std::endl;
}

}  // namespace yarf
