// `luxel health [--service NAME]`: asks luxeld's standard gRPC health service
// (grpc.health.v1.Health/Check) whether it is SERVING. It is the container's
// HEALTHCHECK (Debian packages no grpc_health_probe) and an operator's first
// check. Exit 0 when SERVING, 1 otherwise (not serving, unreachable).
//
// The two messages have one field each, so they are encoded here by hand
// (protobuf wire format: tag = field << 3 | wire type) rather than generating
// stubs for health.proto, which Debian does not ship beside libgrpc++.
#include <grpcpp/generic/generic_stub.h>

#include <cstdio>
#include <future>

#include "commands.h"
#include "remote/connection.h"
#include "remote/output.h"

namespace luxel::cli {
namespace {

using namespace remote;

const char* const kHealthUsage =
    "usage: luxel health [--service NAME] [connection options]\n"
    "  asks luxeld's gRPC health service (grpc.health.v1) whether NAME is SERVING;\n"
    "  exit 0 when it is, 1 otherwise. NAME defaults to luxel.v1.Luxel (NOT_SERVING\n"
    "  once a graceful stop has begun); \"\" asks about the server as a whole\n";

// HealthCheckRequest{string service = 1}: tag 0x0a (field 1, length-delimited).
std::string encode_request(const std::string& service) {
  std::string out;
  if (service.empty()) return out;  // proto3: the default value is not written
  out.push_back('\x0a');
  for (size_t n = service.size();; n >>= 7) {  // varint length
    if (n < 0x80) {
      out.push_back(static_cast<char>(n));
      break;
    }
    out.push_back(static_cast<char>((n & 0x7f) | 0x80));
  }
  return out + service;
}

// HealthCheckResponse{ServingStatus status = 1}: tag 0x08 (field 1, varint);
// absent means 0 (UNKNOWN). Returns -1 for bytes this decoder does not expect.
int decode_status(const std::string& bytes) {
  if (bytes.empty()) return 0;
  if (bytes.size() == 2 && bytes[0] == '\x08' && (bytes[1] & 0x80) == 0) return bytes[1];
  return -1;
}

const char* status_name(int status) {
  switch (status) {
    case 0:
      return "UNKNOWN";
    case 1:
      return "SERVING";
    case 2:
      return "NOT_SERVING";
    case 3:
      return "SERVICE_UNKNOWN";
    default:
      return "UNDECODABLE";
  }
}

}  // namespace

int run_health(const std::vector<std::string>& args) {
  ConnectionOptions copt = default_connection_options();
  copt.timeout_s = 5;  // a probe: fail fast
  std::string service = "luxel.v1.Luxel";
  for (size_t i = 0; i < args.size(); ++i) {
    const OptionMatch m = take_connection_option("health", args, i, copt);
    if (m == OptionMatch::kError) return kExitUsage;
    if (m == OptionMatch::kTaken) continue;
    if (args[i] == "--help" || args[i] == "-h") {
      std::printf("%s%s", kHealthUsage, kConnectionUsage);
      return kExitOk;
    }
    if (args[i] == "--service" && i + 1 < args.size()) {
      service = args[++i];
      continue;
    }
    std::fprintf(stderr, "luxel health: unknown argument or missing value '%s'\n%s",
                 args[i].c_str(), kHealthUsage);
    return kExitUsage;
  }
  auto conn = Connection::open("health", copt);
  if (!conn) return kExitUsage;

  grpc::GenericStub stub(conn->channel());
  grpc::ClientContext ctx;
  conn->prepare_unary(ctx);
  grpc::Slice slice(encode_request(service));
  grpc::ByteBuffer request(&slice, 1), response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&ctx, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&](grpc::Status st) { done.set_value(std::move(st)); });
  const grpc::Status st = done.get_future().get();
  if (!st.ok()) return conn->fail("health", st);  // NOT_FOUND: the service is not registered
  std::vector<grpc::Slice> slices;
  std::string bytes;
  if (response.Dump(&slices).ok())
    for (const auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  const int status = decode_status(bytes);
  if (copt.json)
    print_json_line(
        {{"server", copt.server}, {"service", service}, {"status", status_name(status)}});
  else
    std::printf("%s %s: %s\n", copt.server.c_str(), service.empty() ? "(server)" : service.c_str(),
                status_name(status));
  return status == 1 ? kExitOk : kExitRuntime;
}

}  // namespace luxel::cli
