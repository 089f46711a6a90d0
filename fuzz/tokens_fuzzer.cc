// libFuzzer entry point: the tokens file yarfd reads at start
// (`TOKEN USER ROLE` lines). Contract: ReadTokenFile returns a table or
// throws yarf::Error.
#include <cstddef>
#include <cstdint>

#include "fuzz_file.h"
#include "service/token_auth.h"
#include "yarf/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    yarf::ReadTokenFile(yarf::fuzz::InputFile(data, size, "tokens"));
  } catch (const yarf::Error&) {
    // A malformed file: the expected way to refuse it.
  }
  return 0;
}
