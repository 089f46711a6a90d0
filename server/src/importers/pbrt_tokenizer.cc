#include "importers/pbrt_tokenizer.h"

namespace yarf::importers {
namespace {

bool Space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }
bool Delimiter(char c) { return Space(c) || c == '"' || c == '[' || c == ']' || c == '#'; }

}  // namespace

std::optional<PbrtToken> PbrtTokenizer::Next() {
  if (peeked_) {
    std::optional<PbrtToken> token = std::move(*peeked_);
    peeked_.reset();
    return token;
  }
  return Scan();
}

const std::optional<PbrtToken>& PbrtTokenizer::Peek() {
  if (!peeked_) peeked_ = Scan();
  return *peeked_;
}

std::optional<PbrtToken> PbrtTokenizer::Scan() {
  while (position_ < text_.size()) {
    const char c = text_[position_];
    if (c == '\n') {
      ++line_;
      ++position_;
    } else if (Space(c)) {
      ++position_;
    } else if (c == '#') {
      while (position_ < text_.size() && text_[position_] != '\n') ++position_;
    } else {
      break;
    }
  }
  if (position_ >= text_.size()) return std::nullopt;

  PbrtToken token;
  token.where = {file_, line_};
  const char c = text_[position_];
  if (c == '[' || c == ']') {
    token.kind = c == '[' ? PbrtToken::kOpen : PbrtToken::kClose;
    token.text = c;
    ++position_;
    return token;
  }
  if (c == '"') {
    token.kind = PbrtToken::kString;
    for (++position_;; ++position_) {
      if (position_ >= text_.size() || text_[position_] == '\n') Fail(token.where, "unterminated string");
      char s = text_[position_];
      if (s == '"') break;
      if (s == '\\') {
        if (++position_ >= text_.size()) Fail(token.where, "unterminated string");
        switch (text_[position_]) {
          case 'n': s = '\n'; break;
          case 't': s = '\t'; break;
          case 'b': s = '\b'; break;
          case 'f': s = '\f'; break;
          case 'r': s = '\r'; break;
          default: s = text_[position_];  // \\, \", \' and anything else: the character itself
        }
      }
      token.text += s;
    }
    ++position_;  // the closing quote
    return token;
  }
  const size_t start = position_;
  while (position_ < text_.size() && !Delimiter(text_[position_])) ++position_;
  token.text = std::string(text_.substr(start, position_ - start));
  return token;
}

}  // namespace yarf::importers
