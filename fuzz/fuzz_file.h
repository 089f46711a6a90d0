// For harnesses of readers that take a path: the input written to a file
// of its own in a temporary folder of this process.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace yarf::fuzz {

// `name` in a folder made once per process (and left to the system's
// temporary-file cleaning: a crash must not lose the input anyway).
inline std::filesystem::path InputFile(const uint8_t* data, size_t size, const std::string& name) {
  static const std::filesystem::path folder = [] {
    const std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("yarf-fuzz-" + std::to_string(getpid()));
    std::filesystem::create_directories(path);
    return path;
  }();
  const std::filesystem::path path = folder / name;
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data),
                                                                std::streamsize(size));
  return path;
}

}  // namespace yarf::fuzz
