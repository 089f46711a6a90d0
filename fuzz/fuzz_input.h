// What both fuzzers share: the input is the text of a scene file lying in
// the test scenes' folder; importing it may fail with an ImportError and
// nothing else (no crash, no other exception, no sanitizer report).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string_view>

#include "importers/import.h"

namespace yarf::importers {

template <typename Import>
int FuzzOne(const uint8_t* data, size_t size, const char* file_name, Import import) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    import(text, std::filesystem::path(YARF_FUZZ_SCENE_DIR) / file_name, ImportOptions{});
  } catch (const ImportError&) {
    // A malformed scene: the expected way to refuse it.
  }
  return 0;
}

}  // namespace yarf::importers
