#include "service/server_options.h"

#include <cstdlib>
#include <sstream>

#include "yarf/error.h"

namespace yarf {
namespace {

std::filesystem::path DefaultStateDir() {
  if (const char* dir = std::getenv("YARF_STATE_DIR"); dir && *dir) return dir;
  if (const char* dir = std::getenv("XDG_STATE_HOME"); dir && *dir) return std::filesystem::path(dir) / "yarf";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::filesystem::path(home) / ".local" / "state" / "yarf";
  throw Error("no state folder: set --state-dir, YARF_STATE_DIR or HOME");
}

// "1073741824", "1048576K", "1024M" or "1G".
uint64_t ParseBytes(const std::string& flag, const std::string& value) {
  size_t end = 0;
  unsigned long long number = 0;
  try {
    number = std::stoull(value, &end);
  } catch (const std::exception&) {
    end = 0;
  }
  const std::string suffix = value.substr(end);
  const int shift = suffix.empty() ? 0 : suffix == "K" ? 10 : suffix == "M" ? 20 : suffix == "G" ? 30 : -1;
  if (end == 0 || shift < 0 || number == 0 || number > (uint64_t(1) << (50 - shift)))
    throw Error(flag + " takes a size in bytes, with K, M or G (e.g. 8G), not '" + value + "'");
  return uint64_t(number) << shift;
}

}  // namespace

ServerOptions ParseServerOptions(int argc, char** argv) {
  static const char* kUsage =
      "usage: yarfd [--listen HOST:PORT|unix:PATH] [--port-file FILE] [--plugin-path DIR]...\n"
      "             [--asset-root DIR] [--state-dir DIR] [--threads N] [--component ADDRESS]...\n"
      "             [--component-timeout S]\n"
      "             [--max-running-jobs N] [--checkpoint-seconds S] [--keep-finished-hours H]\n"
      "             [--max-finished-jobs N] [--max-queued-jobs-per-user N]\n"
      "             [--max-instances-per-user N] [--instance-idle-seconds S] [--max-watches-per-user N] [--max-job-memory BYTES[K|M|G]]\n"
      "             [--max-asset-bytes-per-user BYTES[K|M|G]] [--asset-grace-hours H]\n"
      "             [--tls-cert FILE --tls-key FILE] [--tokens FILE] [--allow-load-plugin]\n"
      "             [--allow-root] [--log-json] [--metrics HOST:PORT] [--parent-pid PID]\n"
      "       yarfd --check-requests   (SubmitRequests on stdin, SubmitChecks on stdout)";
  ServerOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") throw Error(kUsage);
    if (flag == "--allow-load-plugin") {
      options.allow_load_plugin = true;
      continue;
    }
    if (flag == "--allow-root") {
      options.allow_root = true;
      continue;
    }
    if (flag == "--log-json") {
      options.log_json = true;
      continue;
    }
    if (flag == "--check-requests") {
      options.check_requests = true;
      continue;
    }
    if (i + 1 >= argc) throw Error("missing value for " + flag + "\n" + kUsage);
    const std::string value = argv[++i];
    if (flag == "--listen") options.listen = value;
    else if (flag == "--port-file") options.port_file = value;
    else if (flag == "--plugin-path") options.plugin_paths.emplace_back(value);
    else if (flag == "--asset-root") options.asset_root = value;
    else if (flag == "--state-dir") options.state_dir = value;
    else if (flag == "--max-running-jobs") options.max_running_jobs = std::atoi(value.c_str());
    else if (flag == "--checkpoint-seconds") options.checkpoint_seconds = std::atof(value.c_str());
    else if (flag == "--keep-finished-hours") options.keep_finished_hours = std::atof(value.c_str());
    else if (flag == "--max-finished-jobs") options.max_finished_jobs = std::atoll(value.c_str());
    else if (flag == "--max-queued-jobs-per-user") options.max_queued_jobs_per_user = std::atoll(value.c_str());
    else if (flag == "--max-instances-per-user") options.max_instances_per_user = std::atoll(value.c_str());
    else if (flag == "--instance-idle-seconds") options.instance_idle_seconds = std::atoll(value.c_str());
    else if (flag == "--max-watches-per-user") options.max_watches_per_user = std::atoll(value.c_str());
    else if (flag == "--max-job-memory") options.max_job_memory = ParseBytes(flag, value);
    else if (flag == "--max-asset-bytes-per-user") options.max_asset_bytes_per_user = ParseBytes(flag, value);
    else if (flag == "--asset-grace-hours") options.asset_grace_hours = std::atof(value.c_str());
    else if (flag == "--threads") options.threads = std::atoi(value.c_str());
    else if (flag == "--component") options.components.push_back(value);
    else if (flag == "--component-timeout") options.component_timeout_seconds = std::atof(value.c_str());
    else if (flag == "--tls-cert") options.tls_cert = value;
    else if (flag == "--tls-key") options.tls_key = value;
    else if (flag == "--tokens") options.tokens_file = value;
    else if (flag == "--metrics") options.metrics = value;
    else if (flag == "--parent-pid") options.parent_pid = std::atoll(value.c_str());
    else throw Error("unknown option " + flag + "\n" + kUsage);
  }
  if (const char* env = std::getenv("YARF_PLUGIN_PATH")) {
    std::stringstream paths(env);
    for (std::string dir; std::getline(paths, dir, ':');)
      if (!dir.empty()) options.plugin_paths.emplace_back(dir);
  }
  if (options.plugin_paths.empty()) options.plugin_paths.emplace_back(YARF_PLUGIN_DIR);
  if (options.state_dir.empty()) options.state_dir = DefaultStateDir();
  if (const char* env = std::getenv("YARF_ALLOW_ROOT"); env && std::string(env) == "1") options.allow_root = true;
  if (options.max_running_jobs < 1) throw Error("--max-running-jobs must be at least 1");
  if (options.parent_pid < 0) throw Error("--parent-pid must be a process id");
  if (!(options.component_timeout_seconds > 0 && options.component_timeout_seconds <= 86400))
    throw Error("--component-timeout must lie in (0, 86400] seconds");
  if (!(options.checkpoint_seconds >= 0)) throw Error("--checkpoint-seconds must be 0 or more");
  if (!(options.keep_finished_hours >= 0)) throw Error("--keep-finished-hours must be 0 or more");
  if (!(options.asset_grace_hours >= 0)) throw Error("--asset-grace-hours must be 0 or more");
  if (options.instance_idle_seconds < 0) throw Error("--instance-idle-seconds must be 0 or more");
  if (options.max_finished_jobs < 0) throw Error("--max-finished-jobs must be 0 or more");
  for (const auto& [flag, value] : {std::pair{"--max-queued-jobs-per-user", options.max_queued_jobs_per_user},
                                    std::pair{"--max-instances-per-user", options.max_instances_per_user},
                                    std::pair{"--max-watches-per-user", options.max_watches_per_user}})
    if (value < 1 || value > (1ll << 30)) throw Error(std::string(flag) + " must lie in [1, 2^30]");
  return options;
}

}  // namespace yarf
