#include "service/rpc_interceptor.h"

#include <google/protobuf/descriptor.h>
#include <grpcpp/server_context.h>

#include <chrono>
#include <map>
#include <mutex>
#include <random>

#include "api/grpc_status_name.h"
#include "common/clock.h"
#include "common/status.h"
#include "service/log.h"

namespace luxel::service {

namespace {

using grpc::experimental::InterceptionHookPoints;
using Clock = std::chrono::steady_clock;

constexpr size_t kMaxRequestIdLength = 64;

// Calls in flight -> their request ids (handlers log with them).
std::mutex g_ids_mu;
std::map<const grpc::ServerContextBase*, std::string> g_ids;

std::string random_request_id() {
  thread_local std::mt19937_64 rng{std::random_device{}()};
  return strprintf("%016llx", static_cast<unsigned long long>(rng()));
}

LogLevel level_of(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return LogLevel::kInfo;
    case grpc::StatusCode::UNKNOWN:
    case grpc::StatusCode::INTERNAL:
    case grpc::StatusCode::DATA_LOSS:
    case grpc::StatusCode::UNIMPLEMENTED:
      return LogLevel::kError;  // the daemon's fault, not the request's
    default:
      return LogLevel::kWarn;
  }
}

// "/luxel.v1.Luxel/SubmitBake" -> "SubmitBake" for methods this daemon
// serves; anything else is "unknown", so a client cannot grow the metric
// label sets with made-up method names.
std::string method_label(const char* full) {
  const std::string m = full ? full : "";
  const size_t slash = m.rfind('/');
  if (m.empty() || m[0] != '/' || slash == 0 || slash == std::string::npos) return "unknown";
  const std::string service = m.substr(1, slash - 1), method = m.substr(slash + 1);
  if (service == "grpc.health.v1.Health" && (method == "Check" || method == "Watch")) return method;
  if (google::protobuf::DescriptorPool::generated_pool()->FindMethodByName(service + "." + method))
    return method;
  return "unknown";
}

const char* stream_kind(const std::string& method) {
  if (method == "UploadScene") return "uploads";
  if (method == "WatchBake") return "watchers";
  if (method == "DownloadResult") return "downloads";
  return nullptr;
}

class RpcInterceptor : public grpc::experimental::Interceptor {
 public:
  RpcInterceptor(grpc::experimental::ServerRpcInfo* info, Metrics* metrics)
      : ctx_(info->server_context()),
        metrics_(metrics),
        method_(method_label(info->method())),
        kind_(stream_kind(method_)),
        id_(random_request_id()),
        start_(Clock::now()) {
    remember();
    if (metrics_ && kind_) metrics_->stream_opened(kind_);
  }

  ~RpcInterceptor() override {
    if (!finished_) finish(grpc::StatusCode::CANCELLED);  // no status sent: the client left
    std::lock_guard<std::mutex> lock(g_ids_mu);
    g_ids.erase(ctx_);
  }

  void Intercept(grpc::experimental::InterceptorBatchMethods* m) override {
    if (m->QueryInterceptionHookPoint(InterceptionHookPoints::POST_RECV_INITIAL_METADATA)) {
      // Here, not at the end: the context is gone by the time the interceptor is.
      if (ctx_) peer_ = ctx_->peer();
      if (auto* md = m->GetRecvInitialMetadata()) {
        auto it = md->find(kRequestIdKey);
        if (it != md->end()) {
          std::string given =
              sanitize_request_id(std::string(it->second.data(), it->second.size()));
          if (!given.empty()) {
            id_ = std::move(given);
            remember();
          }
        }
      }
    }
    if (m->QueryInterceptionHookPoint(InterceptionHookPoints::PRE_SEND_INITIAL_METADATA))
      m->GetSendInitialMetadata()->emplace(kRequestIdKey, id_);
    if (m->QueryInterceptionHookPoint(InterceptionHookPoints::PRE_SEND_STATUS)) {
      m->GetSendTrailingMetadata()->emplace(kRequestIdKey, id_);
      if (!finished_) finish(m->GetSendStatus().error_code());
    }
    m->Proceed();
  }

 private:
  void remember() {
    std::lock_guard<std::mutex> lock(g_ids_mu);
    g_ids[ctx_] = id_;
  }

  void finish(grpc::StatusCode code) {
    finished_ = true;
    // Before the status leaves: a client that has it finds the call counted.
    if (metrics_ && kind_) metrics_->stream_closed(kind_);
    const double seconds = seconds_since(start_);
    if (metrics_) metrics_->rpc_finished(method_, status_code_name(code), seconds);
    log_event(level_of(code), "rpc",
              {{"method", method_},
               {"request_id", id_},
               {"code", status_code_name(code)},
               {"duration_ms", strprintf("%.3f", seconds * 1e3)},
               {"peer", peer_}});
  }

  const grpc::ServerContextBase* ctx_;
  Metrics* metrics_;
  const std::string method_;
  const char* kind_;
  std::string id_;
  std::string peer_;
  const Clock::time_point start_;
  bool finished_ = false;
};

}  // namespace

std::string request_id_of(const grpc::ServerContextBase* ctx) {
  std::lock_guard<std::mutex> lock(g_ids_mu);
  auto it = g_ids.find(ctx);
  return it == g_ids.end() ? std::string() : it->second;
}

std::string sanitize_request_id(const std::string& raw) {
  std::string id;
  for (char c : raw) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == ':' || c == '-';
    if (ok) id += c;
    if (id.size() == kMaxRequestIdLength) break;
  }
  return id;
}

grpc::experimental::Interceptor* RpcInterceptorFactory::CreateServerInterceptor(
    grpc::experimental::ServerRpcInfo* info) {
  return new RpcInterceptor(info, metrics_);
}

}  // namespace luxel::service
