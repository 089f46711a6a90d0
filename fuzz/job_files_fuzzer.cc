// libFuzzer entry point: the checkpoint and result files yarfd keeps in
// its state folder, read back through ReadCheckpoint and ReadJobImage.
// The first byte picks the reader (bit 0) and whether the harness appends
// the file's correct SHA-256 (bit 1), so that inputs reach the parsing
// behind the checksum as well as the checksum itself. Contract: the
// readers return a file or nullopt or throw yarf::Error.
//
// With an argument `--write-seeds=FOLDER` instead writes one valid input
// of each kind there (run.sh does, so the seeds follow the format).
#include <openssl/evp.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <string_view>

#include "fuzz_file.h"
#include "service/job_files.h"
#include "yarf/error.h"

namespace {

// Fixed owners: the fuzzer finds them through its comparison tracing.
constexpr yarf::JobFileOwner kOwner{7, 2};
constexpr size_t kDigestBytes = 32;

std::string WithDigest(std::string_view bytes) {
  std::array<unsigned char, kDigestBytes> digest{};
  unsigned int size = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest.data(), &size, EVP_sha256(), nullptr);
  return std::string(bytes) + std::string(reinterpret_cast<const char*>(digest.data()), digest.size());
}

std::string ReadBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A seed is the selector byte and the file without its digest.
void WriteSeed(const std::filesystem::path& folder, const std::string& name, char selector,
               const std::filesystem::path& file) {
  const std::string bytes = ReadBytes(file);
  std::ofstream(folder / name, std::ios::binary) << selector << bytes.substr(0, bytes.size() - kDigestBytes);
  std::ofstream(folder / (name + "-raw"), std::ios::binary) << char(selector & 1) << bytes;
}

void WriteSeeds(const std::filesystem::path& folder) {
  std::filesystem::create_directories(folder);
  const std::filesystem::path scratch = folder / "scratch";
  yarf::v1::ReconstructionFilter filter;
  yarf::Film film(3, 2, filter);
  yarf::WriteCheckpoint(scratch, kOwner, 16, film.Save());
  WriteSeed(folder, "checkpoint", 2, scratch);
  yarf::JobImage image{3, 2, std::vector<float>(18, 0.5f), std::vector<float>(18, 0.01f)};
  yarf::WriteJobImage(scratch, kOwner, image);
  WriteSeed(folder, "image", 3, scratch);
  std::filesystem::remove(scratch);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  constexpr std::string_view kFlag = "--write-seeds=";
  for (int i = 1; i < *argc; ++i)
    if (std::string_view arg = (*argv)[i]; arg.starts_with(kFlag)) {
      WriteSeeds(std::string(arg.substr(kFlag.size())));
      std::exit(0);
    }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string_view body(reinterpret_cast<const char*>(data + 1), size - 1);
  const std::string bytes = data[0] & 2 ? WithDigest(body) : std::string(body);
  const auto path = yarf::fuzz::InputFile(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), "job-file");
  try {
    if (data[0] & 1) yarf::ReadJobImage(path, kOwner);
    else yarf::ReadCheckpoint(path, kOwner);
  } catch (const yarf::Error&) {
    // A damaged or foreign file: the expected way to refuse it.
  }
  return 0;
}
