#include "service/server_options.h"

#include <cstdlib>
#include <sstream>

#include "yarf/error.h"

namespace yarf {

ServerOptions ParseServerOptions(int argc, char** argv) {
  static const char* kUsage =
      "usage: yarfd [--listen HOST:PORT|unix:PATH] [--port-file FILE] [--plugin-path DIR]...\n"
      "             [--asset-root DIR] [--threads N] [--component ADDRESS]...";
  ServerOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") throw Error(kUsage);
    if (i + 1 >= argc) throw Error("missing value for " + flag + "\n" + kUsage);
    const std::string value = argv[++i];
    if (flag == "--listen") options.listen = value;
    else if (flag == "--port-file") options.port_file = value;
    else if (flag == "--plugin-path") options.plugin_paths.emplace_back(value);
    else if (flag == "--asset-root") options.asset_root = value;
    else if (flag == "--threads") options.threads = std::atoi(value.c_str());
    else if (flag == "--component") options.components.push_back(value);
    else throw Error("unknown option " + flag + "\n" + kUsage);
  }
  if (const char* env = std::getenv("YARF_PLUGIN_PATH")) {
    std::stringstream paths(env);
    for (std::string dir; std::getline(paths, dir, ':');)
      if (!dir.empty()) options.plugin_paths.emplace_back(dir);
  }
  if (options.plugin_paths.empty()) options.plugin_paths.emplace_back(YARF_PLUGIN_DIR);
  return options;
}

}  // namespace yarf
