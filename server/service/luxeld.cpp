// luxeld: the Luxel bake daemon. Serves luxel.v1.Luxel (plus the gRPC health
// service and server reflection) over gRPC, stores scenes and bakes under
// --data-dir, runs bakes on worker threads. See server/service/ and
// `luxeld --help`.
//
// SIGTERM / SIGINT: graceful stop. New uploads and bakes are refused, running
// bakes write a checkpoint and stop (left INTERRUPTED, resumed by the next
// start), open streams end, stores are flushed, exit status 0. A second
// SIGTERM / SIGINT during that stop exits at once with status 128 + signal
// (logged as forced_exit); the next start resumes from the last checkpoints.
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <sys/stat.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <thread>

#include "bake/host_memory.h"
#include "device/context.h"
#include "service/bake_runner.h"
#include "service/bake_store.h"
#include "service/coordinator/coordinator.h"
#include "service/daemon_config.h"
#include "service/data_dir_lock.h"
#include "service/files.h"
#include "service/job_queue.h"
#include "service/log.h"
#include "service/luxel_service.h"
#include "service/metrics.h"
#include "service/parse_error_interceptor.h"
#include "service/rpc_interceptor.h"
#include "service/scene_store.h"

namespace {

using namespace luxel;
using namespace luxel::service;

std::shared_ptr<grpc::ServerCredentials> credentials(const DaemonConfig& c, Status* error) {
  if (c.tls_cert.empty()) return grpc::InsecureServerCredentials();
  auto cert = read_whole_file(c.tls_cert);
  auto key = read_whole_file(c.tls_key);
  if (!cert || !key) {
    *error = invalid_argument("TLS: " + (cert ? key.status() : cert.status()).message());
    return nullptr;
  }
  grpc::SslServerCredentialsOptions ssl;
  ssl.pem_key_cert_pairs.push_back({key.value(), cert.value()});
  return grpc::SslServerCredentials(ssl);
}

bool is_loopback(const std::string& address) {
  return address.rfind("127.", 0) == 0 || address.rfind("localhost:", 0) == 0 ||
         address.rfind("[::1]:", 0) == 0 || address.rfind("unix:", 0) == 0;
}

int run(const DaemonConfig& config) {
  set_log_format(config.log_json ? LogFormat::kJson : LogFormat::kText);
  for (const std::string& w : config.warnings) log_event("warning", {{"message", w}});
  // Before the stores open: they clean up what they take for this daemon's
  // own leftovers (staged uploads, RUNNING bakes to resume).
  auto lock = DataDirLock::acquire(config.data_dir);
  if (!lock) {
    log_event("fatal", {{"error", lock.status().to_string()}});
    return 1;
  }
  // One budget for every import at once: uploads being validated and stored
  // scenes imported for a bake (docs/operations.md "Import budgets").
  scene::ImportMemoryPool import_pool(config.import_memory_budget,
                                      "the daemon's import memory budget (--import-memory-budget)");
  scene::ImportOptions import;
  import.memory_pool = &import_pool;
  import.timeout_seconds = config.import_timeout_s;
  log_event("import_budget", {{"bytes", std::to_string(config.import_memory_budget)},
                              {"timeout_s", strprintf("%g", config.import_timeout_s)}});
  auto scenes = SceneStore::open(config.data_dir, {}, {}, import);
  if (!scenes) {
    log_event("fatal", {{"error", scenes.status().to_string()}});
    return 1;
  }
  auto bakes = BakeStore::open(config.data_dir);
  if (!bakes) {
    log_event("fatal", {{"error", bakes.status().to_string()}});
    return 1;
  }

  std::string device_description;
  pipeline::DeviceLimits device_limits;  // for the estimate at SubmitBake
  if (auto dev = device::choose_device(config.device)) {
    device_description = dev->describe();
    device_limits = pipeline::DeviceLimits::of(dev.value());
  } else {
    device_description = "unavailable: " + dev.status().to_string();
    log_event("device_unavailable", {{"error", dev.status().to_string()}});
  }

  JobQueue queue(config.max_queued);
  // Scrape-time figures; the runner and the service exist before serve().
  BakeRunner* runner_ptr = nullptr;
  LuxelService* service_ptr = nullptr;
  Metrics metrics({
      .queue_depth = [&] { return uint64_t{queue.size()}; },
      .bakes_by_state = [&] { return bakes.value()->count_by_state(); },
      .paths_traced = [&] { return runner_ptr ? runner_ptr->paths_traced() : 0; },
      .upload_bytes = [&] { return service_ptr ? service_ptr->upload_bytes() : 0; },
  });
  RunnerOptions ro;
  ro.metrics = &metrics;
  ro.max_concurrent_bakes = config.max_concurrent_bakes;
  ro.device_spec = config.device;
  ro.auto_intersector = config.intersector == "embree"   ? accel::IntersectorKind::kEmbree
                        : config.intersector == "opencl" ? accel::IntersectorKind::kOpenCl
                                                         : accel::IntersectorKind::kAuto;
  ro.checkpoint_interval_s = config.checkpoint_interval_s;
  ro.limits.max_resolution = config.max_resolution;
  // Coordinator mode: sharded bakes go to the workers (the same token).
  std::unique_ptr<coordinator::Coordinator> coord;
  if (!config.workers.empty() || !config.workers_dns.empty()) {
    coordinator::CoordinatorOptions co;
    co.workers = {config.workers, config.workers_dns, config.token};
    co.grace_s = config.worker_grace_s;
    co.stall_s = config.worker_stall_s;
    co.limits = ro.limits;
    co.metrics = &metrics;
    coord = std::make_unique<coordinator::Coordinator>(*bakes.value(), co);
    ro.coordinator = coord.get();
    const auto workers = coord->pool().resolve();
    std::string list;
    for (const auto& w : workers) list += (list.empty() ? "" : ",") + w;
    log_event(
        "coordinator",
        {{"workers", list}, {"dns", config.workers_dns}, {"grace_s", strprintf("%g", co.grace_s)}});
  }
  BakeRunner runner(*scenes.value(), *bakes.value(), queue, ro);
  if (Status st = runner.recover(); !st.is_ok()) {
    log_event("fatal", {{"error", st.to_string()}});
    return 1;
  }

  ServiceOptions so;
  so.upload.max_upload_bytes = config.max_upload_bytes;
  so.settings = ro.limits;
  so.token = config.token;
  so.device_description = device_description;
  so.device = device_limits;
  so.max_concurrent_bakes = static_cast<uint32_t>(config.max_concurrent_bakes);
  so.host_memory_budget = config.host_memory_budget < 0
                              ? pipeline::default_host_memory_budget()
                              : static_cast<size_t>(config.host_memory_budget);
  so.checkpoints = config.checkpoint_interval_s > 0;
  so.streams = config.streams;
  so.upload_deadlines = {config.upload_idle_timeout_s, config.upload_timeout_s};
  so.metrics = &metrics;
  so.workers = coord ? &coord->pool() : nullptr;
  LuxelService service(*scenes.value(), *bakes.value(), queue, runner, so);
  runner_ptr = &runner;
  service_ptr = &service;
  // Stops the exposer before the runner and the stores it reads go away.
  struct StopMetrics {
    Metrics& m;
    ~StopMetrics() { m.stop_serving(); }
  } stop_metrics{metrics};
  if (!config.metrics_listen.empty()) {
    auto port = metrics.serve(config.metrics_listen);
    if (!port) {
      log_event("fatal", {{"error", port.status().to_string()}});
      runner.shutdown();
      return 1;
    }
    log_event("metrics_listening",
              {{"address", config.metrics_listen}, {"port", std::to_string(port.value())}});
  }

  Status cred_error;
  auto creds = credentials(config, &cred_error);
  if (!creds) {
    log_event("fatal", {{"error", cred_error.to_string()}});
    return 1;
  }
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  // No SO_REUSEPORT: with it a second daemon binds the same port and the
  // kernel spreads connections between the two.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.AddListeningPort(config.listen, creds, &port);
  builder.RegisterService(&service);
  builder.SetMaxReceiveMessageSize(config.max_message_bytes);
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> interceptors;
  // Malformed request bytes: INVALID_ARGUMENT (parse_error_interceptor.h).
  // First, so the status it sets is the one the RPC log line and metrics see.
  interceptors.push_back(make_parse_error_interceptor_factory());
  // Request ids, the per-RPC log line and RPC metrics (rpc_interceptor.h).
  interceptors.push_back(std::make_unique<RpcInterceptorFactory>(&metrics));
  builder.experimental().SetInterceptorCreators(std::move(interceptors));
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) {
    log_event("fatal", {{"error", "cannot listen on " + config.listen +
                                      " (address in use, e.g. by another luxeld, or not an "
                                      "address of this machine)"}});
    runner.shutdown();
    return 1;
  }
  server->GetHealthCheckService()->SetServingStatus("luxel.v1.Luxel", true);
  runner.start();
  log_event("listening", {{"address", config.listen},
                          {"port", std::to_string(port)},
                          {"tls", config.tls_cert.empty() ? "off" : "on"},
                          {"auth", config.token.empty() ? "off" : "bearer"},
                          {"device", device_description},
                          {"host_memory_budget", std::to_string(so.host_memory_budget)},
                          {"data_dir", config.data_dir}});
  if (!is_loopback(config.listen) && config.token.empty())
    log_event("warning", {{"message", "listening beyond loopback without --token"}});

  // Signals are blocked in every thread (see main); this one takes them.
  std::thread signal_thread([&] {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGINT);
    int sig = 0;
    sigwait(&set, &sig);
    log_event("shutdown_requested", {{"signal", sig == SIGTERM ? "SIGTERM" : "SIGINT"}});
    // A second signal while the graceful stop waits (a bake finishing its
    // iteration, a stream draining): exit at once. Every file of the data
    // dir is written atomically (temp + rename) and stray temporaries are
    // removed at the next start, so the store stays consistent; running
    // bakes resume from their last checkpoint.
    std::thread([] {
      sigset_t again;
      sigemptyset(&again);
      sigaddset(&again, SIGTERM);
      sigaddset(&again, SIGINT);
      int second = 0;
      sigwait(&again, &second);
      log_event("forced_exit",
                {{"signal", second == SIGTERM ? "SIGTERM" : "SIGINT"},
                 {"note",
                  "second signal during shutdown; running bakes resume from their last "
                  "checkpoint at the next start"}});
      std::fflush(nullptr);
      std::_Exit(128 + second);
    }).detach();
    service.begin_shutdown();
    server->GetHealthCheckService()->SetServingStatus("luxel.v1.Luxel", false);
    runner.shutdown();  // checkpoints and stops running bakes
    server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(3));
  });
  server->Wait();
  signal_thread.join();
  log_event("stopped", {});
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Block before any thread exists so every thread inherits the mask.
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  std::signal(SIGPIPE, SIG_IGN);

  // Everything the daemon writes (the data dir's scenes, records, results)
  // is private to its user, whatever umask it inherited: directories 0700,
  // files 0600.
  ::umask(077);
  auto config = parse_daemon_args(std::vector<std::string>(argv + 1, argv + argc),
                                  std::getenv("LUXELD_TOKEN"));
  if (!config) {
    std::fprintf(stderr, "luxeld: %s\n%s", config.status().message().c_str(), kDaemonUsage);
    return 2;
  }
  if (config->help) {
    std::fputs(kDaemonUsage, stdout);
    return 0;
  }
  return run(config.value());
}
