// The worker daemons of a coordinator luxeld: a fixed list (--workers
// host:port,...) or the addresses of a DNS name (--workers-dns NAME[:PORT],
// a Kubernetes headless Service, whose A/AAAA records are the ready pods).
// Kubernetes does the scheduling, restarts and discovery; this class only
// resolves the name again whenever a shard needs a worker, so pods that come
// and go are seen without a membership protocol of our own.
#pragma once

#include <grpcpp/grpcpp.h>

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/status.h"
#include "luxel/v1/luxel.grpc.pb.h"

namespace luxel::service::coordinator {

struct WorkerConfig {
  std::vector<std::string> workers;  // --workers: host:port each
  std::string dns;                   // --workers-dns: NAME or NAME:PORT (default port 50051)
  std::string token;                 // bearer token the workers expect (the coordinator's own)
  bool configured() const { return !workers.empty() || !dns.empty(); }
};

// "a:1,b:2" -> {"a:1", "b:2"}; INVALID_ARGUMENT naming --workers for an entry
// without a port.
Result<std::vector<std::string>> parse_worker_list(const std::string& list);

// Every A/AAAA address of `name` (getaddrinfo), as "ip:port" / "[ip6]:port",
// sorted and without duplicates. UNAVAILABLE naming the name when it does
// not resolve.
Result<std::vector<std::string>> resolve_workers_dns(const std::string& name_port);

class WorkerPool {
 public:
  explicit WorkerPool(WorkerConfig config) : config_(std::move(config)) {}
  bool configured() const { return config_.configured(); }
  // The workers now: the fixed list, or the DNS name resolved at this call
  // (an empty list when it does not resolve).
  std::vector<std::string> resolve() const;
  // The last resolve()'s answer (GetServerStatus).
  std::vector<std::string> last_resolved() const;
  // A stub for `address`; channels are kept, so calls share connections.
  std::shared_ptr<v1::Luxel::Stub> stub(const std::string& address);
  // Bearer token metadata and an optional deadline.
  void prepare(grpc::ClientContext& ctx, double deadline_s) const;

 private:
  WorkerConfig config_;
  mutable std::mutex mu_;
  mutable std::vector<std::string> last_;
  std::map<std::string, std::shared_ptr<v1::Luxel::Stub>> stubs_;
};

}  // namespace luxel::service::coordinator
