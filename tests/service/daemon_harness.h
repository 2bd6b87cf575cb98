// Test harness: starts the real luxeld binary (LUXELD_PATH) on a free
// loopback port with a data dir, stops it with a signal, and offers the gRPC
// calls the tests repeat (upload a scene in chunks, wait for a bake state,
// download an artifact).
#pragma once

#include <sys/types.h>

#include <chrono>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "../unit/scene/gltf_builder.h"  // TempDir, and glTF files for uploads
#include "luxel/v1/luxel.grpc.pb.h"

namespace luxel::test {

class Daemon {
 public:
  // Starts luxeld on a free port; waits until it accepts connections.
  // stderr goes to `log_path` (appended, so restarts keep one log).
  Daemon(std::string data_dir, std::vector<std::string> extra_args = {}, std::string token = "");
  ~Daemon();  // SIGKILL if still running

  // Sends `sig` and waits for the process; returns its exit status (or
  // 128+signal when killed). Times out after `timeout` with -1.
  int stop(int sig, std::chrono::seconds timeout = std::chrono::seconds(20));
  // Sends `sig` without waiting (a second signal during a graceful stop).
  void signal(int sig) const;
  // Waits for the process to exit; its status as stop() returns it, -1
  // (process killed) past `timeout`.
  int wait_exit(std::chrono::milliseconds timeout);
  bool running() const { return pid_ > 0; }

  std::unique_ptr<v1::Luxel::Stub> stub() const;
  // A context carrying the token (if any) and a deadline.
  std::unique_ptr<grpc::ClientContext> context(
      std::chrono::seconds deadline = std::chrono::seconds(30)) const;
  const std::string& address() const { return address_; }
  std::string log() const;
  const std::string& data_dir() const { return data_dir_; }

 private:
  std::string data_dir_, token_, address_, log_path_;
  pid_t pid_ = -1;
};

struct Resource {
  std::string uri, bytes;
};

struct UploadOptions {
  std::string sha256_override;  // header sha256 instead of the real one
  long truncate_after = -1;     // send only this many bytes of the payload
  size_t chunk_bytes = 64 * 1024;
  uint64_t size_override = 0;  // header total_size instead of the real one
};

grpc::Status upload_scene(const Daemon& d, const std::string& name, v1::SceneFormat format,
                          const std::string& main_bytes, const std::vector<Resource>& resources,
                          v1::SceneInfo* out, const UploadOptions& options = {});

std::string read_file(const std::string& path);
// Uploads the bundled Cornell box (glTF + buffer); returns its scene id.
std::string upload_cornell(const Daemon& d);
std::string sha256_hex(const std::string& bytes);

// Polls GetBake until `done(info)` or the timeout; returns the last info.
v1::BakeInfo wait_for_bake(const Daemon& d, const std::string& bake_id,
                           bool (*done)(const v1::BakeInfo&),
                           std::chrono::seconds timeout = std::chrono::seconds(60));
bool is_finished(const v1::BakeInfo& info);

// Downloads an artifact; checks the chunked stream (total_size in the first
// message, sha256 in the last) and returns the bytes and the sent checksum.
grpc::Status download(const Daemon& d, const std::string& bake_id, const std::string& artifact,
                      std::string* bytes, std::string* sha256, uint64_t* total_size);

// A unary call with raw request bytes (malformed protobufs, services
// without generated stubs here, e.g. grpc.health.v1.Health).
grpc::Status raw_unary(const Daemon& d, const std::string& method, const std::string& request,
                       std::string* response);

// One request on a bidi stream with raw bytes; the first response's bytes
// (grpc.reflection.v1alpha.ServerReflection).
grpc::Status raw_bidi_once(const Daemon& d, const std::string& method, const std::string& request,
                           std::string* response);

// Small settings most tests use: 64x64, `spp` samples, progress and
// snapshots every 0.1 s.
v1::BakeSettings small_settings(uint32_t spp, uint32_t resolution = 64);
// SubmitBake and CancelBake, expected to succeed (a failure is reported
// and the reply is empty).
v1::BakeInfo submit_bake(const Daemon& d, const std::string& scene_id, const v1::BakeSettings& s);
v1::BakeInfo cancel_bake(const Daemon& d, const std::string& bake_id);

}  // namespace luxel::test
