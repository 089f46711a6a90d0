// yarfd's command line.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace yarf {

// The largest message yarfd receives or sends (a batch, a job's result).
inline constexpr int kMaxMessageBytes = 256 << 20;

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";
  std::filesystem::path port_file;
  std::vector<std::filesystem::path> plugin_paths;
  std::filesystem::path asset_root;
  // Where the server keeps what outlives it: the job database, film
  // checkpoints, results and uploaded assets. --state-dir, else
  // $YARF_STATE_DIR, else $XDG_STATE_HOME/yarf, else ~/.local/state/yarf.
  std::filesystem::path state_dir;
  // The job queue: jobs rendering at once, least seconds between two
  // checkpoints of a rendering film, and how long and how many ended jobs
  // are kept (the oldest go first).
  int max_running_jobs = 2;
  double checkpoint_seconds = 5;
  double keep_finished_hours = 168;
  long long max_finished_jobs = 1000;
  int threads = 0;  // 0: all cores
  // Component processes whose classes are made for good (no lease).
  std::vector<std::string> components;
  // Deadline, in seconds, of each call to an instance Factory.Create made
  // in a component process (a job's calls take its component_timeout_seconds).
  double component_timeout_seconds = 60;
  // TLS certificate chain and private key (PEM), and the bearer-token file:
  // required when --listen is reachable from other machines.
  std::filesystem::path tls_cert;
  std::filesystem::path tls_key;
  std::filesystem::path tokens_file;
  // What one user may hold at once: jobs not ended, Factory instances and
  // open Watch streams.
  long long max_queued_jobs_per_user = 1000;
  long long max_instances_per_user = 1000;
  // A user's instances unused this long are released when they need room.
  long long instance_idle_seconds = 3600;
  long long max_watches_per_user = 1000;
  // The most memory a job may be estimated to need (bytes; 0: half the
  // machine's). --max-job-memory takes a K, M or G suffix.
  uint64_t max_job_memory = 0;
  // Uploaded assets: at most this many bytes per user, and those no job
  // still to run names are deleted when unused for the grace period.
  uint64_t max_asset_bytes_per_user = uint64_t(20) << 30;
  double asset_grace_hours = 24;
  // Registry.LoadPlugin: off unless asked for, and then only for files
  // directly inside a --plugin-path folder (loading runs the library's
  // code as yarfd's user).
  bool allow_load_plugin = false;
  // yarfd refuses to run as root unless --allow-root (or YARF_ALLOW_ROOT=1).
  bool allow_root = false;
  // One line per job event on stderr (job_events.h): key=value text, or
  // with --log-json one JSON object per line.
  bool log_json = false;
  // The process that started yarfd, when it is to stop with it (0: none).
  int64_t parent_pid = 0;
  // --metrics HOST:PORT: Prometheus metrics over HTTP at /metrics there;
  // empty (the default): none.
  std::string metrics;
  // --check-requests: serve no port, only answer SubmitRequests on stdin
  // with the checks Submit makes (ServeRequestChecks).
  bool check_requests = false;
};

// Throws Error with usage for an unknown or incomplete flag.
ServerOptions ParseServerOptions(int argc, char** argv);

}  // namespace yarf
