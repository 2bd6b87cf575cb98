// Maps gRPC's status for a request whose bytes do not parse to
// INVALID_ARGUMENT with a message.
//
// gRPC C++ parses a request before the handler runs; when protobuf parsing
// fails (grpc::GenericDeserialize) the call ends with INTERNAL and the
// message's InitializationErrorString(), which for a proto3 message is empty
// ("Did not read entire message" when bytes are left over). For a callback
// server-streaming method (WatchBake) it is UNIMPLEMENTED without a message
// instead. The application never sees the request. A server interceptor does
// see the status about to be sent (PRE_SEND_STATUS) and may replace it.
// Luxel's own handlers never send INTERNAL without a message, so for
// luxel.v1 methods an INTERNAL with one of those two messages, or an
// UNIMPLEMENTED without a message from WatchBake (an rpc the service does
// implement), is a parse failure.
//
// Streaming requests of the callback API (UploadScene's chunks) are not
// covered: a chunk that does not parse completes the read with ok == false,
// the same as the end of the stream, and the upload ends with the status of
// a short upload (DATA_LOSS).
#pragma once

#include <grpcpp/support/server_interceptor.h>

#include <memory>

namespace luxel::service {

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>
make_parse_error_interceptor_factory();

}  // namespace luxel::service
