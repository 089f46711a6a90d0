// Where a construct of a scene file sits, and the error a malformed file
// raises: both importers report problems as "file:line: message".
#pragma once

#include <stdexcept>
#include <string>

namespace yarf::importers {

struct SourceLocation {
  std::string file;  // as the user named it (or relative to the scene folder)
  int line = 0;      // 1-based; 0 when unknown

  std::string ToString() const { return line > 0 ? file + ":" + std::to_string(line) : file; }
};

// Messages quote the file's text, which may hold line breaks and control
// characters; a message stays one line.
inline std::string OneLine(std::string text) {
  for (char& c : text)
    if (static_cast<unsigned char>(c) < 0x20) c = ' ';
  return text;
}

// A scene file that cannot be imported: truncated, mistyped, cyclic,
// pointing outside its folder or at something missing. what() is one line,
// "file:line: message".
class ImportError : public std::runtime_error {
 public:
  ImportError(const SourceLocation& where, const std::string& message)
      : std::runtime_error(OneLine(where.ToString() + ": " + message)), where_(where) {}
  const SourceLocation& where() const { return where_; }

 private:
  SourceLocation where_;
};

[[noreturn]] inline void Fail(const SourceLocation& where, const std::string& message) {
  throw ImportError(where, message);
}

}  // namespace yarf::importers
