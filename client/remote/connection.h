// How the `luxel` CLI reaches a luxeld daemon: the options every remote
// command shares (--server, --token, --tls-ca, --json, --timeout), the gRPC
// channel built from them, and the one place that turns a failed call into a
// message and an exit code.
#pragma once

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>
#include <vector>

#include "api/grpc_status_name.h"
#include "luxel/v1/luxel.grpc.pb.h"

namespace luxel::cli::remote {

// Exit codes of the remote commands (documented in `luxel --help`).
inline constexpr int kExitOk = 0;
inline constexpr int kExitRuntime = 1;     // the daemon or the network failed a call
inline constexpr int kExitUsage = 2;       // bad command line
inline constexpr int kExitBakeFailed = 3;  // the bake ended FAILED, CANCELLED or INTERRUPTED

struct ConnectionOptions {
  std::string server = "127.0.0.1:50051";  // host:port ($LUXEL_SERVER)
  std::string token;                       // bearer token ($LUXEL_TOKEN); empty = none
  std::string tls_ca_file;                 // PEM root certificates; non-empty turns TLS on
  bool tls = false;                        // TLS with the system's root certificates
  bool json = false;                       // one JSON object per line on stdout
  double timeout_s = 30;                   // deadline of unary calls
};

// The defaults, with $LUXEL_SERVER and $LUXEL_TOKEN applied.
ConnectionOptions default_connection_options();

enum class OptionMatch { kNotMine, kTaken, kError };

// If args[i] is one of the shared options, consumes it (and its value,
// advancing i) into `options`. kError has printed "luxel CMD: ..." to stderr.
OptionMatch take_connection_option(const char* cmd, const std::vector<std::string>& args, size_t& i,
                                   ConnectionOptions& options);

// Usage lines for the shared options, for each command's --help.
extern const char* const kConnectionUsage;

class Connection {
 public:
  // Reads the TLS root certificates (when asked for) and creates the channel;
  // it connects lazily, on the first call. Returns nullptr after printing
  // the reason when the certificate file cannot be read.
  static std::unique_ptr<Connection> open(const char* cmd, const ConnectionOptions& options);

  luxel::v1::Luxel::Stub& stub() { return *stub_; }
  // For calls outside luxel.v1 (the health service, through a GenericStub).
  std::shared_ptr<grpc::Channel> channel() const { return channel_; }
  const ConnectionOptions& options() const { return options_; }

  // Adds the bearer token and, for unary calls, the deadline.
  void prepare_unary(grpc::ClientContext& ctx) const;
  void prepare_stream(grpc::ClientContext& ctx) const;

  // Prints why a call failed ("luxel CMD: cannot reach luxeld at
  // 127.0.0.1:50051 (UNAVAILABLE): ...", "luxel CMD: NOT_FOUND: ...")
  // and returns kExitRuntime.
  int fail(const char* cmd, const grpc::Status& status) const;

 private:
  Connection(ConnectionOptions options, std::shared_ptr<grpc::Channel> channel);
  ConnectionOptions options_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<luxel::v1::Luxel::Stub> stub_;
};

using luxel::status_code_name;  // api/grpc_status_name.h

}  // namespace luxel::cli::remote
