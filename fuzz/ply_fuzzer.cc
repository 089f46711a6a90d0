// libFuzzer entry point: PLY mesh files (ASCII and binary). Contract: the
// reader returns a valid mesh or throws yarf::Error, within the time and
// memory limits, whatever counts the header declares.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "kernel/mesh_io.h"
#include "yarf/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    yarf::ParseMesh(std::string_view(reinterpret_cast<const char*>(data), size), "ply", "fuzz.ply");
  } catch (const yarf::Error&) {
    // A malformed file: the expected way to refuse it.
  }
  return 0;
}
