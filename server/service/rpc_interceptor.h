// One gRPC server interceptor for every call (luxel.v1, health, reflection):
//   - a request id per RPC: the client's "x-request-id" metadata when it
//     sends a usable one (kept: letters, digits, '.', '_', ':', '-', at most
//     64), else 16 random hex digits; returned in the response's initial and
//     trailing metadata as "x-request-id";
//   - one log line when the RPC ends: event=rpc with method, request_id,
//     code, duration_ms and peer;
//   - metrics (metrics.h): RPC count and duration by method and code, open
//     streams by kind.
// Handlers find their call's id with request_id_of(ctx) (LuxelService puts
// it on the thread's log lines, log.h).
#pragma once

#include <grpcpp/support/server_interceptor.h>

#include <memory>
#include <string>

#include "service/metrics.h"

namespace luxel::service {

inline constexpr const char* kRequestIdKey = "x-request-id";

// "" when the call has no id (no interceptor installed).
std::string request_id_of(const grpc::ServerContextBase* ctx);

// The client's value cleaned up (see above); "" when nothing usable is left.
std::string sanitize_request_id(const std::string& raw);

class RpcInterceptorFactory : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  explicit RpcInterceptorFactory(Metrics* metrics) : metrics_(metrics) {}
  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override;

 private:
  Metrics* metrics_;  // may be null
};

}  // namespace luxel::service
