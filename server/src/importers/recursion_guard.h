// Bounds recursion through references (a texture or material that names
// itself, directly or not), so a malformed file fails instead of
// overflowing the stack.
#pragma once

#include "importers/import_error.h"

namespace yarf::importers {

class RecursionGuard {
 public:
  static constexpr int kMaxDepth = 64;

  RecursionGuard(int& depth, const SourceLocation& where) : depth_(depth) {
    if (depth_ >= kMaxDepth) Fail(where, "references nested too deeply (a cycle of references?)");
    ++depth_;
  }
  ~RecursionGuard() { --depth_; }
  RecursionGuard(const RecursionGuard&) = delete;
  RecursionGuard& operator=(const RecursionGuard&) = delete;

 private:
  int& depth_;
};

}  // namespace yarf::importers
