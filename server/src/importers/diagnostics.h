// Warnings of an import: what was ignored or approximated, and where.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "importers/import_error.h"

namespace yarf::importers {

// " (did you mean 'reflectance'?)" when `word` is one or two edits from
// one of `known` (the nearest), else "": for misspelt names and types.
std::string DidYouMean(const std::string& word, const std::vector<std::string>& known);

class Diagnostics {
 public:
  // Records a warning. Warnings with the same key are reported once, at
  // their first place, with a count of the other places.
  void Warn(const SourceLocation& where, const std::string& key, const std::string& message);
  void Warn(const SourceLocation& where, const std::string& message) { Warn(where, message, message); }

  // "file:line: message", one per distinct key, in the order first seen.
  std::vector<std::string> Lines() const;

 private:
  struct Entry {
    SourceLocation where;
    std::string message;
    int more = 0;
  };
  std::vector<Entry> entries_;
  std::map<std::string, size_t> by_key_;
};

}  // namespace yarf::importers
