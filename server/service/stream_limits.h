// Caps on the daemon's long-lived streams (uploads, watchers, downloads), in
// total and per client, so that a client holding streams open cannot take
// every thread, file descriptor or staging folder of the daemon.
//
// "Client" is the peer's host (ServerContextBase::peer() without the port):
// the daemon has one bearer token shared by every authorised client, so the
// token would make all of them one client. Past a cap the call gets
// RESOURCE_EXHAUSTED naming the cap and the flag that sets it.
#pragma once

#include <grpcpp/grpcpp.h>

#include <cstdint>
#include <map>
#include <mutex>
#include <string>

namespace luxel::service {

enum class StreamKind { kUpload = 0, kWatch = 1, kDownload = 2 };

struct StreamCaps {
  uint32_t max_uploads = 16, max_uploads_per_client = 4;
  uint32_t max_watchers = 256, max_watchers_per_client = 64;
  uint32_t max_downloads = 32, max_downloads_per_client = 8;
};

// "ipv4:10.0.0.7:5123" -> "10.0.0.7", "ipv6:[::1]:5123" -> "[::1]",
// "unix:/path" stays whole.
std::string peer_host(const std::string& peer);

class StreamSlots;

// One held slot; released when destroyed (or moved from).
class StreamSlot {
 public:
  StreamSlot() = default;
  StreamSlot(StreamSlot&& other) noexcept { *this = std::move(other); }
  StreamSlot& operator=(StreamSlot&& other) noexcept;
  ~StreamSlot() { release(); }
  void release();
  bool held() const { return owner_ != nullptr; }

 private:
  friend class StreamSlots;
  StreamSlots* owner_ = nullptr;
  StreamKind kind_ = StreamKind::kUpload;
  std::string client_;
};

class StreamSlots {
 public:
  explicit StreamSlots(StreamCaps caps) : caps_(caps) {}

  // OK and a held slot, or RESOURCE_EXHAUSTED naming the cap and its flag.
  grpc::Status acquire(StreamKind kind, const std::string& client, StreamSlot* slot);
  uint32_t open(StreamKind kind) const;
  const StreamCaps& caps() const { return caps_; }

 private:
  friend class StreamSlot;
  void release(StreamKind kind, const std::string& client);

  const StreamCaps caps_;
  mutable std::mutex mu_;
  uint32_t total_[3] = {0, 0, 0};
  std::map<std::string, uint32_t> per_client_[3];
};

}  // namespace luxel::service
