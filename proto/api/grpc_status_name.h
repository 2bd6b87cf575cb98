// The canonical name of a gRPC status code ("NOT_FOUND", "UNAVAILABLE",
// ...), for the CLI's messages and the daemon's logs and metric labels.
// gRPC C++ has no such function.
#pragma once

#include <grpcpp/support/status.h>

namespace luxel {

// "UNKNOWN_CODE" for a value outside grpc::StatusCode.
const char* status_code_name(grpc::StatusCode code);

}  // namespace luxel
