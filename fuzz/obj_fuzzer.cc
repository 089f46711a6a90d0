// libFuzzer entry point: OBJ mesh files, through tinyobjloader (compiled
// here with the same instrumentation). Contract: the reader returns a
// valid mesh or throws yarf::Error, within the time and memory limits,
// whatever indices and lines the file holds.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "kernel/mesh_io.h"
#include "yarf/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    yarf::ParseMesh(std::string_view(reinterpret_cast<const char*>(data), size), "obj", "fuzz.obj");
  } catch (const yarf::Error&) {
    // A malformed file: the expected way to refuse it.
  }
  return 0;
}
