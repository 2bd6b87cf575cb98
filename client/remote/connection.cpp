#include "remote/connection.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace luxel::cli::remote {

const char* const kConnectionUsage =
    "connection options (every remote command):\n"
    "  --server HOST:PORT    luxeld address (default $LUXEL_SERVER or 127.0.0.1:50051)\n"
    "  --token T             bearer token (default $LUXEL_TOKEN)\n"
    "  --tls-ca FILE         use TLS, trusting the PEM root certificates in FILE\n"
    "  --tls                 use TLS with the system's root certificates\n"
    "  --timeout S           deadline of each request/response call (default 30)\n"
    "  --json                machine-readable output: one JSON object per line\n";

ConnectionOptions default_connection_options() {
  ConnectionOptions o;
  if (const char* s = std::getenv("LUXEL_SERVER"); s && *s) o.server = s;
  if (const char* t = std::getenv("LUXEL_TOKEN"); t && *t) o.token = t;
  return o;
}

OptionMatch take_connection_option(const char* cmd, const std::vector<std::string>& args, size_t& i,
                                   ConnectionOptions& o) {
  const std::string& k = args[i];
  const bool needs_value = k == "--server" || k == "--token" || k == "--tls-ca" || k == "--timeout";
  if (k == "--json") {
    o.json = true;
    return OptionMatch::kTaken;
  }
  if (k == "--tls") {
    o.tls = true;
    return OptionMatch::kTaken;
  }
  if (!needs_value) return OptionMatch::kNotMine;
  if (i + 1 >= args.size()) {
    std::fprintf(stderr, "luxel %s: %s needs a value\n", cmd, k.c_str());
    return OptionMatch::kError;
  }
  const std::string& v = args[++i];
  if (k == "--server") {
    if (v.empty() || v.find(':') == std::string::npos) {
      std::fprintf(stderr, "luxel %s: --server expects HOST:PORT, got '%s'\n", cmd, v.c_str());
      return OptionMatch::kError;
    }
    o.server = v;
  } else if (k == "--token") {
    o.token = v;
  } else if (k == "--tls-ca") {
    o.tls_ca_file = v;
  } else {
    char* end = nullptr;
    o.timeout_s = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(o.timeout_s) || o.timeout_s <= 0) {
      std::fprintf(stderr, "luxel %s: --timeout expects seconds > 0, got '%s'\n", cmd, v.c_str());
      return OptionMatch::kError;
    }
  }
  return OptionMatch::kTaken;
}

std::unique_ptr<Connection> Connection::open(const char* cmd, const ConnectionOptions& options) {
  std::shared_ptr<grpc::ChannelCredentials> creds;
  if (!options.tls_ca_file.empty()) {
    std::ifstream in(options.tls_ca_file, std::ios::binary);
    std::stringstream pem;
    pem << in.rdbuf();
    if (!in || pem.str().empty()) {
      std::fprintf(stderr, "luxel %s: cannot read the TLS root certificates '%s'\n", cmd,
                   options.tls_ca_file.c_str());
      return nullptr;
    }
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = pem.str();
    creds = grpc::SslCredentials(ssl);
  } else if (options.tls) {
    creds = grpc::SslCredentials(grpc::SslCredentialsOptions());
  } else {
    creds = grpc::InsecureChannelCredentials();
  }
  grpc::ChannelArguments args;
  // Snapshots of large float lightmaps exceed gRPC's 4 MiB default; the
  // daemon enforces its own limits, the client accepts what it is sent.
  args.SetMaxReceiveMessageSize(512 << 20);
  args.SetMaxSendMessageSize(64 << 20);
  auto channel = grpc::CreateCustomChannel(options.server, creds, args);
  return std::unique_ptr<Connection>(new Connection(options, std::move(channel)));
}

Connection::Connection(ConnectionOptions options, std::shared_ptr<grpc::Channel> channel)
    : options_(std::move(options)),
      channel_(std::move(channel)),
      stub_(luxel::v1::Luxel::NewStub(channel_)) {}

void Connection::prepare_stream(grpc::ClientContext& ctx) const {
  if (!options_.token.empty()) ctx.AddMetadata("authorization", "Bearer " + options_.token);
}

void Connection::prepare_unary(grpc::ClientContext& ctx) const {
  prepare_stream(ctx);
  ctx.set_deadline(std::chrono::system_clock::now() +
                   std::chrono::milliseconds(static_cast<int64_t>(options_.timeout_s * 1000)));
}

int Connection::fail(const char* cmd, const grpc::Status& st) const {
  const char* code = status_code_name(st.error_code());
  const std::string& msg = st.error_message();
  switch (st.error_code()) {
    case grpc::StatusCode::UNAVAILABLE:
      std::fprintf(stderr, "luxel %s: cannot reach luxeld at %s (%s): %s\n", cmd,
                   options_.server.c_str(), code, msg.c_str());
      break;
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      // The daemon's own limits (--import-timeout, --upload-timeout) send a
      // message of their own; gRPC's for this client's deadline is this one.
      if (msg != "Deadline Exceeded") {
        std::fprintf(stderr, "luxel %s: %s: %s\n", cmd, code, msg.c_str());
        break;
      }
      std::fprintf(stderr, "luxel %s: luxeld at %s did not answer within %g s (%s): %s\n", cmd,
                   options_.server.c_str(), options_.timeout_s, code, msg.c_str());
      break;
    case grpc::StatusCode::UNAUTHENTICATED:
      std::fprintf(stderr, "luxel %s: %s: %s (%s)\n", cmd, code, msg.c_str(),
                   options_.token.empty() ? "pass --token or set LUXEL_TOKEN"
                                          : "check --token / LUXEL_TOKEN");
      break;
    default:
      std::fprintf(stderr, "luxel %s: %s: %s\n", cmd, code, msg.c_str());
  }
  return kExitRuntime;
}

}  // namespace luxel::cli::remote
