// Prometheus metrics of the daemon (--metrics-listen HOST:PORT serves them
// as text at /metrics; without the flag they are kept but not served).
//
// Two kinds of figures:
//   - pushed by hooks as things happen: RPCs (rpc_interceptor.h), finished
//     bakes, download bytes, open streams, running bakes' progress;
//   - pulled at scrape time from the daemon's own state (Sources): queue
//     depth, bakes by state, paths traced, upload bytes. Counters among them
//     advance by the difference since the last scrape.
// The engine knows nothing of this; the service and the runner call in.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "common/status.h"

namespace prometheus {
class Exposer;
class Registry;
class Collectable;
}  // namespace prometheus

namespace luxel::service {

class Metrics {
 public:
  struct Sources {
    std::function<uint64_t()> queue_depth;
    std::function<std::map<std::string, uint64_t>()> bakes_by_state;  // "BAKE_STATE_X" -> n
    std::function<uint64_t()> paths_traced;
    std::function<uint64_t()> upload_bytes;
  };

  explicit Metrics(Sources sources);
  ~Metrics();
  Metrics(const Metrics&) = delete;
  Metrics& operator=(const Metrics&) = delete;

  // Serves /metrics on `address` (HOST:PORT, numeric host). INVALID_ARGUMENT
  // naming --metrics-listen for a malformed address, UNAVAILABLE when it
  // cannot bind. Returns the bound port.
  Result<int> serve(const std::string& address);
  // Stops serving (before what the Sources read is destroyed).
  void stop_serving();

  // `method` is the short name ("SubmitBake"), `code` the gRPC code name.
  void rpc_finished(const std::string& method, const std::string& code, double seconds);
  // Open streaming RPCs by kind: "uploads", "watchers", "downloads".
  void stream_opened(const std::string& kind);
  void stream_closed(const std::string& kind);
  void download_bytes(uint64_t bytes);
  // A running bake's latest progress (rate and device memory gauges).
  void bake_progress(const std::string& bake_id, uint64_t paths, double elapsed_s,
                     uint64_t device_bytes);
  // The bake left the device; `outcome` labels the duration histogram
  // ("samples", "time", "error", "stopped", "cancelled", "interrupted", "failed").
  void bake_ended(const std::string& bake_id, const std::string& outcome, double seconds);

  // Coordinator mode (coordinator/coordinator.h): a shard event ("submitted",
  // "lost", "reattached", "reassigned", "downloaded", "finish_asked"), a
  // shard's accumulators downloaded, and a bake's merge cost by step.
  void shard_event(const std::string& event);
  void shard_downloaded(uint64_t bytes, double seconds);
  void shards_merged(double read_s, double fold_s, double finish_s);

  // Text exposition of every metric (what a scrape returns).
  std::string render();

 private:
  class Impl;
  std::shared_ptr<Impl> impl_;
  std::unique_ptr<prometheus::Exposer> exposer_;
};

// "HOST:PORT" split and checked: a numeric IPv4 address or [IPv6] and a port
// in [1, 65535]. INVALID_ARGUMENT naming `flag` otherwise.
Status check_listen_address(const std::string& flag, const std::string& address);

}  // namespace luxel::service
