// libFuzzer entry point: Mitsuba 3 XML scene text.
#include "fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return yarf::importers::FuzzOne(data, size, "fuzz-input.xml", yarf::importers::ImportMitsuba);
}
