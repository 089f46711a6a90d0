// libFuzzer entry point: Mitsuba serialized mesh files. The first byte
// picks the shape to decode (0-3), the rest is the file. Contract: the
// reader returns a mesh or throws ImportError, within the time and memory
// limits, whatever the counts, offsets and zlib streams say.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "importers/serialized_mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const yarf::importers::SourceLocation where{"fuzz.xml", 1};
  try {
    yarf::importers::DecodeSerializedMesh(std::string_view(reinterpret_cast<const char*>(data + 1), size - 1),
                                          data[0] % 4, where);
  } catch (const yarf::importers::ImportError&) {
    // A malformed file: the expected way to refuse it.
  }
  return 0;
}
