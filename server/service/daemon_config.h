// luxeld's command line. parse_daemon_args never exits: --help and errors
// come back as a Status / flag so main() decides the exit code.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"
#include "scene/import_budget.h"
#include "service/stream_limits.h"

namespace luxel::service {

struct DaemonConfig {
  std::string listen = "127.0.0.1:50051";  // loopback unless told otherwise
  std::string data_dir;                    // required
  int max_concurrent_bakes = 1;
  std::string device;  // OpenCL device spec ("" = LUXEL_DEVICE, then default)
  // What settings.intersector = auto means on this daemon: "auto" (Embree on
  // CPU devices, the OpenCL kernels on GPUs), "embree" or "opencl".
  std::string intersector = "auto";
  std::string token;  // bearer token ("" = no authentication)
  // --allow-readable-token-file: start although the token file's mode lets
  // its group or everyone read it (with a warning instead of a refusal).
  bool allow_readable_token_file = false;
  std::vector<std::string> warnings;  // for main() to log once logging is set up
  std::string tls_cert, tls_key;      // PEM files; both or neither
  uint64_t max_upload_bytes = uint64_t{1} << 30;
  // Bytes all imports running at once may allocate (scene/import_budget.h;
  // default 1/8 of the machine's or the cgroup's memory) and the seconds one
  // import may run.
  uint64_t import_memory_budget = scene::default_import_memory_budget();
  double import_timeout_s = 300;
  int max_resolution = 4096;
  // --host-memory-budget: host bytes one bake may be estimated to need at
  // SubmitBake (bake/host_memory.h); -1: half the machine's memory or the
  // cgroup's limit, 0: not checked.
  double host_memory_budget = -1;
  size_t max_queued = 256;
  double checkpoint_interval_s = 10;
  int max_message_bytes = 16 << 20;   // largest request message accepted
  StreamCaps streams;                 // --max-uploads, --max-watchers, ... (per client too)
  double upload_idle_timeout_s = 60;  // an upload that sends nothing this long ends
  double upload_timeout_s = 3600;     // an upload not complete after this ends; 0: none
  std::string metrics_listen;         // Prometheus /metrics HOST:PORT ("" = off)
  bool log_json = false;              // --log-format json (one JSON object per line)
  // Coordinator mode (server/service/coordinator/): sharded bakes go to these
  // worker daemons. --workers host:port,... or --workers-dns NAME[:PORT].
  std::vector<std::string> workers;
  std::string workers_dns;
  double worker_grace_s = 60;   // --worker-grace: a lost worker is retried this long
  double worker_stall_s = 300;  // --worker-stall-timeout: no progress this long = lost
  bool help = false;
};

extern const char* kDaemonUsage;

// INVALID_ARGUMENT naming the flag. The token comes from --token-file or
// `token_env` (the LUXELD_TOKEN environment variable; nullptr when unset),
// never from argv, where every user of the machine can read it.
Result<DaemonConfig> parse_daemon_args(const std::vector<std::string>& args,
                                       const char* token_env = nullptr);

}  // namespace luxel::service
