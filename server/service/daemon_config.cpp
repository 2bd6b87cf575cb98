#include "service/daemon_config.h"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "service/coordinator/worker_pool.h"
#include "service/files.h"
#include "service/metrics.h"

namespace luxel::service {

namespace {

uint32_t* stream_cap(StreamCaps& caps, const std::string& flag) {
  if (flag == "--max-uploads") return &caps.max_uploads;
  if (flag == "--max-uploads-per-client") return &caps.max_uploads_per_client;
  if (flag == "--max-watchers") return &caps.max_watchers;
  if (flag == "--max-watchers-per-client") return &caps.max_watchers_per_client;
  if (flag == "--max-downloads") return &caps.max_downloads;
  if (flag == "--max-downloads-per-client") return &caps.max_downloads_per_client;
  return nullptr;
}

}  // namespace

const char* kDaemonUsage =
    "usage: luxeld --data-dir DIR [options]\n"
    "  --listen HOST:PORT        address to serve on (default 127.0.0.1:50051, loopback)\n"
    "  --data-dir DIR            scenes, bake records, checkpoints and results (required)\n"
    "  --max-concurrent-bakes N  bakes running at once (default 1)\n"
    "  --device SPEC             OpenCL device: gpu, cpu, P:D or a name substring\n"
    "  --intersector auto|embree|opencl  ray queries of bakes whose settings say auto\n"
    "                            (default auto: Embree on CPU devices, OpenCL on GPUs)\n"
    "  --token-file FILE         require \"authorization: Bearer TOKEN\" on every call, TOKEN\n"
    "                            read from FILE (trailing newline ignored); or set the\n"
    "                            LUXELD_TOKEN environment variable. Never on the command\n"
    "                            line, where every user sees it in ps. FILE must not be\n"
    "                            readable by its group or others (chmod 600)\n"
    "  --allow-readable-token-file  start anyway when it is (with a warning)\n"
    "  --tls-cert PEM --tls-key PEM   serve TLS instead of plaintext\n"
    "  --max-upload-bytes N      largest scene upload, main file + resources (default 1 GiB)\n"
    "  --import-memory-budget B  bytes every upload and scene import running at once may\n"
    "                            allocate, e.g. 3GiB, 512MiB (default 1/8 of the machine's\n"
    "                            or cgroup's memory); past it RESOURCE_EXHAUSTED\n"
    "  --import-timeout S        seconds one scene import may run (default 300); past it\n"
    "                            DEADLINE_EXCEEDED\n"
    "  --max-resolution N        largest lightmap side in texels (default 4096)\n"
    "  --max-queued N            most bakes waiting in the queue (default 256)\n"
    "  --host-memory-budget N    host bytes a bake may be estimated to need; SubmitBake refuses\n"
    "                            more with RESOURCE_EXHAUSTED (default half the machine's\n"
    "                            memory or the cgroup's memory.max; 0 = no check)\n"
    "  --checkpoint-interval S   seconds between bake checkpoints (default 10; 0 = none)\n"
    "  --max-message-bytes N     largest request message (default 16 MiB)\n"
    "  --max-uploads N           uploads open at once, all clients (default 16)\n"
    "  --max-uploads-per-client N  uploads open at once from one client host (default 4)\n"
    "  --max-watchers N          WatchBake streams open at once (default 256)\n"
    "  --max-watchers-per-client N  WatchBake streams from one client host (default 64)\n"
    "  --max-downloads N         DownloadResult streams open at once (default 32)\n"
    "  --max-downloads-per-client N  DownloadResult streams from one client host (default 8)\n"
    "                            past a cap a call gets RESOURCE_EXHAUSTED naming the flag\n"
    "  --upload-idle-timeout S   end an upload that sends nothing for S seconds with\n"
    "                            DEADLINE_EXCEEDED and discard it (default 60)\n"
    "  --upload-timeout S        end an upload not complete after S seconds (default 3600;\n"
    "                            0 = no limit)\n"
    "  --metrics-listen HOST:PORT  serve Prometheus metrics at http://HOST:PORT/metrics\n"
    "                            (numeric address, e.g. 127.0.0.1:9464; default off)\n"
    "  --log-format text|json    log lines on stderr: key=value (default) or JSON objects\n"
    "  --workers HOST:PORT,...   coordinator mode: bakes with settings.shards > 1 are split\n"
    "                            across these worker luxelds and merged exactly\n"
    "  --workers-dns NAME[:PORT] coordinator mode with the workers at every A/AAAA address\n"
    "                            of NAME (a Kubernetes headless Service), resolved again\n"
    "                            whenever a shard needs a worker (default port 50051)\n"
    "  --worker-grace S          a worker that stops answering is retried this long before\n"
    "                            its shard goes to another worker (default 60)\n"
    "  --worker-stall-timeout S  a running shard with no new paths this long goes to another\n"
    "                            worker (default 300)\n";

Result<DaemonConfig> parse_daemon_args(const std::vector<std::string>& args,
                                       const char* token_env) {
  DaemonConfig c;
  std::string token_file;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& k = args[i];
    std::string v;
    auto value = [&]() -> Status {
      if (i + 1 >= args.size()) return invalid_argument(k + ": needs a value");
      v = args[++i];
      return Status::ok();
    };
    auto number = [&](double lo, double hi, double* out) -> Status {
      LUXEL_RETURN_IF_ERROR(value());
      char* end = nullptr;
      errno = 0;
      const double x = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || errno != 0 || !std::isfinite(x) || x < lo || x > hi)
        return invalid_argument(
            strprintf("%s: expected a number in [%g, %g], got '%s'", k.c_str(), lo, hi, v.c_str()));
      *out = x;
      return Status::ok();
    };
    double x = 0;
    if (k == "--help" || k == "-h")
      c.help = true;
    else if (k == "--listen") {
      LUXEL_RETURN_IF_ERROR(value());
      c.listen = v;
    } else if (k == "--data-dir") {
      LUXEL_RETURN_IF_ERROR(value());
      c.data_dir = v;
    } else if (k == "--device") {
      LUXEL_RETURN_IF_ERROR(value());
      c.device = v;
    } else if (k == "--intersector") {
      LUXEL_RETURN_IF_ERROR(value());
      if (v != "auto" && v != "embree" && v != "opencl")
        return invalid_argument("--intersector: auto, embree or opencl, got '" + v + "'");
      c.intersector = v;
    } else if (k == "--token") {
      // A token in argv shows in ps and /proc/PID/cmdline to every user.
      return invalid_argument(
          "--token: not accepted on the command line (it would show in ps); put the token in "
          "a file for --token-file or in the LUXELD_TOKEN environment variable");
    } else if (k == "--token-file") {
      LUXEL_RETURN_IF_ERROR(value());
      token_file = v;
    } else if (k == "--allow-readable-token-file") {
      c.allow_readable_token_file = true;
    } else if (k == "--tls-cert") {
      LUXEL_RETURN_IF_ERROR(value());
      c.tls_cert = v;
    } else if (k == "--tls-key") {
      LUXEL_RETURN_IF_ERROR(value());
      c.tls_key = v;
    } else if (k == "--max-concurrent-bakes") {
      LUXEL_RETURN_IF_ERROR(number(1, 64, &x));
      c.max_concurrent_bakes = int(x);
    } else if (k == "--max-upload-bytes") {
      LUXEL_RETURN_IF_ERROR(number(1, 1e15, &x));
      c.max_upload_bytes = uint64_t(x);
    } else if (k == "--import-memory-budget") {
      LUXEL_RETURN_IF_ERROR(value());
      auto bytes = scene::parse_byte_size(v);
      if (!bytes) return invalid_argument(k + ": " + bytes.status().message());
      if (*bytes < (uint64_t{1} << 20))
        return invalid_argument(k + ": '" + v + "' is below the smallest budget, 1MiB");
      c.import_memory_budget = *bytes;
    } else if (k == "--import-timeout") {
      LUXEL_RETURN_IF_ERROR(number(0.001, 1e6, &x));
      c.import_timeout_s = x;
    } else if (k == "--max-resolution") {
      LUXEL_RETURN_IF_ERROR(number(1, 65536, &x));
      c.max_resolution = int(x);
    } else if (k == "--host-memory-budget") {
      // The same byte sizes as --import-memory-budget ("8GiB"); 0: no check.
      LUXEL_RETURN_IF_ERROR(value());
      auto bytes = scene::parse_byte_size(v);
      if (!bytes) return invalid_argument(k + ": " + bytes.status().message());
      c.host_memory_budget = *bytes;
    } else if (k == "--max-queued") {
      LUXEL_RETURN_IF_ERROR(number(1, 1e6, &x));
      c.max_queued = size_t(x);
    } else if (k == "--checkpoint-interval") {
      LUXEL_RETURN_IF_ERROR(number(0, 1e6, &x));
      c.checkpoint_interval_s = x;
    } else if (k == "--max-message-bytes") {
      LUXEL_RETURN_IF_ERROR(number(1024, 2147483647.0, &x));
      c.max_message_bytes = int(x);
    } else if (uint32_t* cap = stream_cap(c.streams, k)) {
      LUXEL_RETURN_IF_ERROR(number(1, 1e5, &x));
      *cap = uint32_t(x);
    } else if (k == "--upload-idle-timeout") {
      LUXEL_RETURN_IF_ERROR(number(0.1, 1e6, &x));
      c.upload_idle_timeout_s = x;
    } else if (k == "--upload-timeout") {
      LUXEL_RETURN_IF_ERROR(number(0, 1e7, &x));
      c.upload_timeout_s = x;
    } else if (k == "--metrics-listen") {
      LUXEL_RETURN_IF_ERROR(value());
      LUXEL_RETURN_IF_ERROR(check_listen_address(k, v));
      c.metrics_listen = v;
    } else if (k == "--log-format") {
      LUXEL_RETURN_IF_ERROR(value());
      if (v != "text" && v != "json")
        return invalid_argument("--log-format: expected 'text' or 'json', got '" + v + "'");
      c.log_json = v == "json";
    } else if (k == "--workers") {
      LUXEL_RETURN_IF_ERROR(value());
      auto list = coordinator::parse_worker_list(v);
      if (!list) return list.status();
      c.workers = list.value();
    } else if (k == "--workers-dns") {
      LUXEL_RETURN_IF_ERROR(value());
      if (v.empty()) return invalid_argument("--workers-dns: needs a name");
      c.workers_dns = v;
    } else if (k == "--worker-grace") {
      LUXEL_RETURN_IF_ERROR(number(0, 1e6, &x));
      c.worker_grace_s = x;
    } else if (k == "--worker-stall-timeout") {
      LUXEL_RETURN_IF_ERROR(number(1, 1e6, &x));
      c.worker_stall_s = x;
    } else
      return invalid_argument(strprintf("unknown option '%s'", k.c_str()));
  }
  if (c.help) return c;
  if (c.data_dir.empty()) return invalid_argument("--data-dir: required");
  if (!c.workers.empty() && !c.workers_dns.empty())
    return invalid_argument("--workers and --workers-dns: give one");
  if (c.tls_cert.empty() != c.tls_key.empty())
    return invalid_argument("--tls-cert and --tls-key go together");
  if (token_env != nullptr) {
    // Set but empty is a mistake, not a request to run without auth.
    if (!token_file.empty())
      return invalid_argument("--token-file and LUXELD_TOKEN both give a token; use one");
    c.token = token_env;
    if (c.token.empty())
      return invalid_argument(
          "LUXELD_TOKEN is set but empty; unset it to run without auth, or give a token");
  }
  if (!token_file.empty()) {
    // The token is the daemon's only secret: a copy other local users can
    // read lets them call every rpc.
    struct stat st {};
    if (::stat(token_file.c_str(), &st) == 0 && (st.st_mode & (S_IRGRP | S_IROTH)) != 0) {
      const std::string what =
          strprintf("--token-file: %s has mode %04o: readable by %s", token_file.c_str(),
                    static_cast<unsigned>(st.st_mode & 07777),
                    (st.st_mode & S_IROTH) != 0 ? "every user" : "its group");
      if (!c.allow_readable_token_file)
        return invalid_argument(what + "; chmod 600 it, or pass --allow-readable-token-file");
      c.warnings.push_back(what + " (allowed by --allow-readable-token-file)");
    }
    auto t = read_whole_file(token_file);
    if (!t) return invalid_argument("--token-file: " + t.status().message());
    c.token = t.value();
    while (!c.token.empty() && (c.token.back() == '\n' || c.token.back() == '\r'))
      c.token.pop_back();
    if (c.token.empty()) return invalid_argument("--token-file: " + token_file + " is empty");
  }
  return c;
}

}  // namespace luxel::service
