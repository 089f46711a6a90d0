#include "importers/diagnostics.h"

#include <algorithm>

namespace yarf::importers {
namespace {

// Levenshtein distance (insertions, deletions, substitutions).
size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string DidYouMean(const std::string& word, const std::vector<std::string>& known) {
  // Names longer than any the formats use are not worth comparing.
  if (word.size() > 64) return "";
  const std::string* best = nullptr;
  size_t best_distance = 3;
  for (const std::string& k : known)
    if (const size_t d = EditDistance(word, k); d > 0 && d < best_distance) best = &k, best_distance = d;
  return best ? " (did you mean '" + *best + "'?)" : "";
}

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
