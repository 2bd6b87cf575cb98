#include "service/metrics.h"

#include <prometheus/collectable.h>
#include <prometheus/counter.h>
#include <prometheus/exposer.h>
#include <prometheus/gauge.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>
#include <prometheus/text_serializer.h>

#include <cctype>
#include <cstdlib>

namespace luxel::service {

using prometheus::Counter;
using prometheus::Family;
using prometheus::Gauge;
using prometheus::Histogram;

namespace {

// Bakes run from well under a second (tests) to hours (production).
const Histogram::BucketBoundaries kBakeBuckets = {0.1, 0.5, 1,   5,    10,   30,
                                                  60,  300, 900, 3600, 14400};
// Unary calls take milliseconds; streams (uploads, watchers) minutes.
const Histogram::BucketBoundaries kRpcBuckets = {0.0005, 0.001, 0.005, 0.01, 0.05, 0.1,
                                                 0.5,    1,     5,     30,   120,  600};

// "BAKE_STATE_RUNNING" -> "running".
std::string state_label(const std::string& name) {
  std::string s = name.rfind("BAKE_STATE_", 0) == 0 ? name.substr(11) : name;
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

class Metrics::Impl : public prometheus::Collectable {
 public:
  explicit Impl(Sources s)
      : sources(std::move(s)),
        registry(std::make_shared<prometheus::Registry>()),
        queue_depth(prometheus::BuildGauge()
                        .Name("luxel_queue_depth")
                        .Help("Bakes waiting in the queue for a worker")
                        .Register(*registry)
                        .Add({})),
        bakes(prometheus::BuildGauge()
                  .Name("luxel_bakes")
                  .Help("Bakes known to the daemon, by state")
                  .Register(*registry)),
        bake_seconds(prometheus::BuildHistogram()
                         .Name("luxel_bake_duration_seconds")
                         .Help("Tracing time of bakes that left the device, by outcome")
                         .Register(*registry)),
        paths_total(prometheus::BuildCounter()
                        .Name("luxel_paths_traced_total")
                        .Help("Light paths traced by all bakes since the daemon started")
                        .Register(*registry)
                        .Add({})),
        paths_rate(prometheus::BuildGauge()
                       .Name("luxel_paths_per_second")
                       .Help("Paths per second of the running bakes (last progress interval)")
                       .Register(*registry)
                       .Add({})),
        device_bytes(prometheus::BuildGauge()
                         .Name("luxel_device_memory_bytes")
                         .Help("Device buffers held by the running bakes")
                         .Register(*registry)
                         .Add({})),
        upload_total(prometheus::BuildCounter()
                         .Name("luxel_upload_bytes_total")
                         .Help("Scene bytes received by UploadScene")
                         .Register(*registry)
                         .Add({})),
        download_total(prometheus::BuildCounter()
                           .Name("luxel_download_bytes_total")
                           .Help("Artifact bytes sent by DownloadResult")
                           .Register(*registry)
                           .Add({})),
        rpcs(prometheus::BuildCounter()
                 .Name("luxel_rpc_requests_total")
                 .Help("RPCs finished, by method and gRPC status code")
                 .Register(*registry)),
        rpc_seconds(prometheus::BuildHistogram()
                        .Name("luxel_rpc_duration_seconds")
                        .Help("RPC duration from its first byte to its status, by method and code")
                        .Register(*registry)),
        streams(prometheus::BuildGauge()
                    .Name("luxel_active_streams")
                    .Help("Open streaming RPCs by kind")
                    .Register(*registry)),
        shard_events(prometheus::BuildCounter()
                         .Name("luxel_coordinator_shard_events_total")
                         .Help("Coordinator mode: shard events (submitted, lost, reattached, "
                               "reassigned, downloaded, finish_asked)")
                         .Register(*registry)),
        shard_bytes(prometheus::BuildCounter()
                        .Name("luxel_coordinator_shard_bytes_total")
                        .Help("Coordinator mode: accumulators.bin bytes downloaded from workers")
                        .Register(*registry)
                        .Add({})),
        shard_download_seconds(prometheus::BuildHistogram()
                                   .Name("luxel_coordinator_shard_download_seconds")
                                   .Help("Coordinator mode: one shard's accumulators download")
                                   .Register(*registry)
                                   .Add({}, kRpcBuckets)),
        merge_seconds(prometheus::BuildCounter()
                          .Name("luxel_coordinator_merge_seconds_total")
                          .Help("Coordinator mode: seconds merging shards, by step (read, fold, "
                                "finish)")
                          .Register(*registry)) {
    for (const char* kind : {"uploads", "watchers", "downloads"}) streams.Add({{"kind", kind}});
  }

  // Scrape: the pulled figures first, then everything.
  std::vector<prometheus::MetricFamily> Collect() const override {
    std::lock_guard<std::mutex> lock(mu);
    if (sources.queue_depth) queue_depth.Set(static_cast<double>(sources.queue_depth()));
    if (sources.bakes_by_state)
      for (const auto& [state, n] : sources.bakes_by_state())
        bakes.Add({{"state", state_label(state)}}).Set(static_cast<double>(n));
    advance(paths_total, sources.paths_traced, &paths_seen);
    advance(upload_total, sources.upload_bytes, &upload_seen);
    double rate = 0, bytes = 0;
    for (const auto& [id, r] : running) {
      rate += r.rate;
      bytes += static_cast<double>(r.device_bytes);
    }
    paths_rate.Set(rate);
    device_bytes.Set(bytes);
    return registry->Collect();
  }

  // A pulled counter moves by what its source gained since the last scrape.
  static void advance(Counter& c, const std::function<uint64_t()>& source, uint64_t* seen) {
    if (!source) return;
    const uint64_t now = source();
    if (now > *seen) c.Increment(static_cast<double>(now - *seen));
    *seen = std::max(*seen, now);
  }

  struct RunningBake {
    uint64_t paths = 0;
    double elapsed_s = 0;
    double rate = 0;
    uint64_t device_bytes = 0;
  };

  Sources sources;
  std::shared_ptr<prometheus::Registry> registry;
  Gauge& queue_depth;
  Family<Gauge>& bakes;
  Family<Histogram>& bake_seconds;
  Counter& paths_total;
  Gauge& paths_rate;
  Gauge& device_bytes;
  Counter& upload_total;
  Counter& download_total;
  Family<Counter>& rpcs;
  Family<Histogram>& rpc_seconds;
  Family<Gauge>& streams;
  Family<Counter>& shard_events;
  Counter& shard_bytes;
  Histogram& shard_download_seconds;
  Family<Counter>& merge_seconds;

  mutable std::mutex mu;  // the fields below
  mutable uint64_t paths_seen = 0, upload_seen = 0;
  std::map<std::string, RunningBake> running;
};

Metrics::Metrics(Sources sources) : impl_(std::make_shared<Impl>(std::move(sources))) {}

Metrics::~Metrics() = default;

Status check_listen_address(const std::string& flag, const std::string& address) {
  auto bad = [&](const std::string& why) {
    return invalid_argument(strprintf("%s: %s, got '%s' (expected HOST:PORT, e.g. 127.0.0.1:9464)",
                                      flag.c_str(), why.c_str(), address.c_str()));
  };
  const size_t colon = address.rfind(':');
  if (colon == std::string::npos) return bad("no port");
  const std::string host = address.substr(0, colon), port = address.substr(colon + 1);
  if (port.empty() || port.size() > 5 ||
      port.find_first_not_of("0123456789") != std::string::npos || std::atoi(port.c_str()) > 65535)
    return bad("port must be a number in [0, 65535]");
  if (host.empty()) return bad("no host (use 0.0.0.0 for every interface)");
  if (host.front() == '[') {
    if (host.back() != ']' || host.size() < 3 ||
        host.find_first_not_of("0123456789abcdefABCDEF:.", 1) != host.size() - 1)
      return bad("not a numeric IPv6 address in brackets");
    return Status::ok();
  }
  int parts = 0;
  size_t start = 0;
  for (;;) {
    const size_t dot = host.find('.', start);
    const std::string part = host.substr(start, dot == std::string::npos ? dot : dot - start);
    if (part.empty() || part.size() > 3 ||
        part.find_first_not_of("0123456789") != std::string::npos || std::atoi(part.c_str()) > 255)
      return bad("host must be a numeric IPv4 address or [IPv6]");
    ++parts;
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  if (parts != 4) return bad("host must be a numeric IPv4 address or [IPv6]");
  return Status::ok();
}

Result<int> Metrics::serve(const std::string& address) {
  LUXEL_RETURN_IF_ERROR(check_listen_address("--metrics-listen", address));
  try {
    exposer_ = std::make_unique<prometheus::Exposer>(address, /*num_threads=*/1);
  } catch (const std::exception& e) {
    return Status(StatusCode::kUnavailable,
                  strprintf("--metrics-listen: cannot listen on %s (%s; address in use, or not an "
                            "address of this machine)",
                            address.c_str(), e.what()));
  }
  exposer_->RegisterCollectable(impl_);
  const auto ports = exposer_->GetListeningPorts();
  return ports.empty() ? 0 : ports.front();
}

void Metrics::stop_serving() {
  exposer_.reset();
}

void Metrics::rpc_finished(const std::string& method, const std::string& code, double seconds) {
  impl_->rpcs.Add({{"method", method}, {"code", code}}).Increment();
  impl_->rpc_seconds.Add({{"method", method}, {"code", code}}, kRpcBuckets).Observe(seconds);
}

void Metrics::stream_opened(const std::string& kind) {
  impl_->streams.Add({{"kind", kind}}).Increment();
}

void Metrics::stream_closed(const std::string& kind) {
  impl_->streams.Add({{"kind", kind}}).Decrement();
}

void Metrics::download_bytes(uint64_t bytes) {
  impl_->download_total.Increment(static_cast<double>(bytes));
}

void Metrics::bake_progress(const std::string& bake_id, uint64_t paths, double elapsed_s,
                            uint64_t device_bytes) {
  std::lock_guard<std::mutex> lock(impl_->mu);
  Impl::RunningBake& r = impl_->running[bake_id];
  if (elapsed_s > r.elapsed_s && paths >= r.paths && r.elapsed_s > 0)
    r.rate = static_cast<double>(paths - r.paths) / (elapsed_s - r.elapsed_s);
  else if (r.elapsed_s == 0 && elapsed_s > 0)
    r.rate = static_cast<double>(paths) / elapsed_s;
  r.paths = paths;
  r.elapsed_s = elapsed_s;
  r.device_bytes = device_bytes;
}

void Metrics::bake_ended(const std::string& bake_id, const std::string& outcome, double seconds) {
  {
    std::lock_guard<std::mutex> lock(impl_->mu);
    impl_->running.erase(bake_id);
  }
  impl_->bake_seconds.Add({{"outcome", outcome}}, kBakeBuckets).Observe(seconds);
}

void Metrics::shard_event(const std::string& event) {
  impl_->shard_events.Add({{"event", event}}).Increment();
}

void Metrics::shard_downloaded(uint64_t bytes, double seconds) {
  impl_->shard_bytes.Increment(static_cast<double>(bytes));
  impl_->shard_download_seconds.Observe(seconds);
}

void Metrics::shards_merged(double read_s, double fold_s, double finish_s) {
  impl_->merge_seconds.Add({{"step", "read"}}).Increment(read_s);
  impl_->merge_seconds.Add({{"step", "fold"}}).Increment(fold_s);
  impl_->merge_seconds.Add({{"step", "finish"}}).Increment(finish_s);
}

std::string Metrics::render() {
  return prometheus::TextSerializer().Serialize(impl_->Collect());
}

}  // namespace luxel::service
