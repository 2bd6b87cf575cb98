#include "service/coordinator/worker_pool.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <sys/socket.h>

#include <algorithm>
#include <chrono>

namespace luxel::service::coordinator {

Result<std::vector<std::string>> parse_worker_list(const std::string& list) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= list.size()) {
    size_t comma = list.find(',', start);
    if (comma == std::string::npos) comma = list.size();
    std::string w = list.substr(start, comma - start);
    start = comma + 1;
    if (w.empty()) continue;
    const size_t colon = w.rfind(':');
    if (colon == std::string::npos || colon + 1 == w.size() ||
        w.find_first_not_of("0123456789", colon + 1) != std::string::npos)
      return invalid_argument("--workers: expected host:port entries, got '" + w + "'");
    if (std::find(out.begin(), out.end(), w) == out.end()) out.push_back(w);
  }
  if (out.empty()) return invalid_argument("--workers: no worker given");
  return out;
}

Result<std::vector<std::string>> resolve_workers_dns(const std::string& name_port) {
  std::string name = name_port, port = "50051";
  // NAME:PORT, unless NAME is a bare IPv6 literal (more than one colon).
  if (const size_t colon = name_port.rfind(':');
      colon != std::string::npos && name_port.find(':') == colon) {
    name = name_port.substr(0, colon);
    port = name_port.substr(colon + 1);
  }
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  if (int rc = getaddrinfo(name.c_str(), port.c_str(), &hints, &res); rc != 0)
    return Status(StatusCode::kUnavailable, strprintf("--workers-dns: cannot resolve '%s': %s",
                                                      name.c_str(), gai_strerror(rc)));
  std::vector<std::string> out;
  for (addrinfo* a = res; a; a = a->ai_next) {
    char host[INET6_ADDRSTRLEN] = {};
    if (a->ai_family == AF_INET) {
      inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(a->ai_addr)->sin_addr, host, sizeof host);
      out.push_back(std::string(host) + ":" + port);
    } else if (a->ai_family == AF_INET6) {
      inet_ntop(AF_INET6, &reinterpret_cast<sockaddr_in6*>(a->ai_addr)->sin6_addr, host,
                sizeof host);
      out.push_back("[" + std::string(host) + "]:" + port);
    }
  }
  freeaddrinfo(res);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<std::string> WorkerPool::resolve() const {
  std::vector<std::string> now = config_.workers;
  if (!config_.dns.empty()) {
    auto r = resolve_workers_dns(config_.dns);
    now = r ? r.value() : std::vector<std::string>{};
  }
  std::lock_guard<std::mutex> lock(mu_);
  last_ = now;
  return now;
}

std::vector<std::string> WorkerPool::last_resolved() const {
  std::lock_guard<std::mutex> lock(mu_);
  return last_.empty() ? config_.workers : last_;
}

std::shared_ptr<v1::Luxel::Stub> WorkerPool::stub(const std::string& address) {
  std::lock_guard<std::mutex> lock(mu_);
  auto& s = stubs_[address];
  if (!s) {
    grpc::ChannelArguments args;
    // Accumulators and EXR snapshots exceed gRPC's 4 MiB default.
    args.SetMaxReceiveMessageSize(512 << 20);
    args.SetMaxSendMessageSize(64 << 20);
    // A restarted worker must be reconnected to quickly (fault grace period).
    args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 200);
    args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 1000);
    s = v1::Luxel::NewStub(
        grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args));
  }
  return s;
}

void WorkerPool::prepare(grpc::ClientContext& ctx, double deadline_s) const {
  if (!config_.token.empty()) ctx.AddMetadata("authorization", "Bearer " + config_.token);
  if (deadline_s > 0)
    ctx.set_deadline(std::chrono::system_clock::now() +
                     std::chrono::milliseconds(static_cast<int64_t>(deadline_s * 1000)));
}

}  // namespace luxel::service::coordinator
