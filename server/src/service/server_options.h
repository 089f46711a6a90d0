// yarfd's command line.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace yarf {

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";
  std::filesystem::path port_file;
  std::vector<std::filesystem::path> plugin_paths;
  std::filesystem::path asset_root;
  int threads = 0;  // 0: all cores
  // Component processes whose classes are made for good (no lease).
  std::vector<std::string> components;
};

// Throws Error with usage for an unknown or incomplete flag.
ServerOptions ParseServerOptions(int argc, char** argv);

}  // namespace yarf
