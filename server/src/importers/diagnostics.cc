#include "importers/diagnostics.h"

namespace yarf::importers {

void Diagnostics::Warn(const SourceLocation& where, const std::string& key, const std::string& message) {
  const auto [it, inserted] = by_key_.emplace(key, entries_.size());
  if (inserted)
    entries_.push_back({where, message, 0});
  else
    ++entries_[it->second].more;
}

std::vector<std::string> Diagnostics::Lines() const {
  std::vector<std::string> lines;
  for (const Entry& e : entries_) {
    std::string line = e.where.ToString() + ": " + e.message;
    if (e.more > 0)
      line += " (and " + std::to_string(e.more) + " more place" + (e.more > 1 ? "s" : "") + ")";
    lines.push_back(OneLine(std::move(line)));
  }
  return lines;
}

}  // namespace yarf::importers
