// libFuzzer entry point: irradiance_cache's cache_file, read back and its
// records put to use (added to the cache, an estimate made). The key the
// file must carry is taken from the input itself, so that inputs reach
// the records. Contract: Read returns false for a file it cannot use, and
// what it returns is safe to use (no NaN, no sanitizer report).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fuzz_file.h"
#include "irradiance_records.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  uint64_t key = 0;
  if (size >= 24) std::memcpy(&key, data + 16, sizeof key);
  std::vector<yarf::IrradianceRecord> records;
  if (!yarf::irradiance_file::Read(yarf::fuzz::InputFile(data, size, "records.irc").string(), key, records))
    return 0;
  yarf::IrradianceRecords cache(0.2f, 1.0f);
  for (const yarf::IrradianceRecord& record : records) cache.Add(record);
  const yarf::Vec3 estimate = cache.Estimate(yarf::Vec3(0, 0, 0), yarf::Vec3(0, 0, 1));
  if (!std::isfinite(estimate.x + estimate.y + estimate.z)) __builtin_trap();
  return 0;
}
