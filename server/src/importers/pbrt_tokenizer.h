// Tokens of the pbrt-v4 scene format: words (directives, numbers, bare
// booleans), quoted strings, '[' and ']'; '#' comments run to the end of
// the line.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "importers/import_error.h"

namespace yarf::importers {

struct PbrtToken {
  enum Kind { kWord, kString, kOpen, kClose };
  Kind kind = kWord;
  std::string text;  // a string's content, escapes resolved
  SourceLocation where;
};

class PbrtTokenizer {
 public:
  // `text` must outlive the tokenizer; `file` names it in locations.
  PbrtTokenizer(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {}

  // The next token, or nullopt at the end. Fails on an unterminated string.
  std::optional<PbrtToken> Next();
  // The next token without consuming it.
  const std::optional<PbrtToken>& Peek();
  // Where the tokenizer stands (for "ends early" errors).
  SourceLocation Here() const { return {file_, line_}; }

 private:
  std::optional<PbrtToken> Scan();

  std::string_view text_;
  std::string file_;
  size_t position_ = 0;
  int line_ = 1;
  std::optional<std::optional<PbrtToken>> peeked_;
};

}  // namespace yarf::importers
