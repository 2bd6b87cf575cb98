#include "service/parse_error_interceptor.h"

#include <string>

namespace luxel::service {

namespace {

using grpc::experimental::InterceptionHookPoints;

class ParseErrorInterceptor final : public grpc::experimental::Interceptor {
 public:
  explicit ParseErrorInterceptor(std::string method) : method_(std::move(method)) {}

  bool is_parse_failure(const grpc::Status& sent) const {
    const std::string& m = sent.error_message();
    if (sent.error_code() == grpc::StatusCode::INTERNAL)
      return m.empty() || m == "Did not read entire message";
    // A callback server-streaming handler (WatchBake) whose request does not
    // parse never creates our reactor; gRPC ends the call with UNIMPLEMENTED
    // and no message instead (CallbackServerStreamingHandler::RunHandler).
    return sent.error_code() == grpc::StatusCode::UNIMPLEMENTED && m.empty() &&
           method_ == "/luxel.v1.Luxel/WatchBake";
  }

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(InterceptionHookPoints::PRE_SEND_STATUS)) {
      const grpc::Status sent = methods->GetSendStatus();
      if (is_parse_failure(sent))
        methods->ModifySendStatus(
            grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                         "request: the message bytes do not parse as the request of " + method_ +
                             " (malformed protobuf)"));
    }
    methods->Proceed();
  }

 private:
  const std::string method_;
};

class Factory final : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override {
    const std::string method = info->method() != nullptr ? info->method() : "";
    if (method.rfind("/luxel.v1.Luxel/", 0) != 0) return nullptr;
    return new ParseErrorInterceptor(method);
  }
};

}  // namespace

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>
make_parse_error_interceptor_factory() {
  return std::make_unique<Factory>();
}

}  // namespace luxel::service
