// libFuzzer entry point: pbrt-v4 scene text.
#include "fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return yarf::importers::FuzzOne(data, size, "fuzz-input.pbrt", yarf::importers::ImportPbrt);
}
