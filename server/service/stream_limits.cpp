#include "service/stream_limits.h"

#include "common/status.h"

namespace luxel::service {

namespace {

struct CapInfo {
  const char* what;  // in the message: "uploads", "watchers", "downloads"
  const char* total_flag;
  const char* client_flag;
};

constexpr CapInfo kInfo[3] = {
    {"uploads", "--max-uploads", "--max-uploads-per-client"},
    {"watchers", "--max-watchers", "--max-watchers-per-client"},
    {"downloads", "--max-downloads", "--max-downloads-per-client"},
};

}  // namespace

std::string peer_host(const std::string& peer) {
  if (peer.rfind("unix:", 0) == 0) return peer;
  std::string rest = peer;
  if (auto colon = rest.find(':'); colon != std::string::npos && rest.rfind("ip", 0) == 0)
    rest = rest.substr(colon + 1);  // drop "ipv4:" / "ipv6:"
  if (!rest.empty() && rest[0] == '[') {
    auto close = rest.find(']');
    return close == std::string::npos ? rest : rest.substr(0, close + 1);
  }
  auto colon = rest.rfind(':');
  return colon == std::string::npos ? rest : rest.substr(0, colon);
}

StreamSlot& StreamSlot::operator=(StreamSlot&& other) noexcept {
  if (this != &other) {
    release();
    owner_ = other.owner_;
    kind_ = other.kind_;
    client_ = std::move(other.client_);
    other.owner_ = nullptr;
  }
  return *this;
}

void StreamSlot::release() {
  if (owner_ != nullptr) owner_->release(kind_, client_);
  owner_ = nullptr;
}

grpc::Status StreamSlots::acquire(StreamKind kind, const std::string& client, StreamSlot* slot) {
  const int k = static_cast<int>(kind);
  const uint32_t caps[3][2] = {{caps_.max_uploads, caps_.max_uploads_per_client},
                               {caps_.max_watchers, caps_.max_watchers_per_client},
                               {caps_.max_downloads, caps_.max_downloads_per_client}};
  std::lock_guard<std::mutex> lock(mu_);
  uint32_t& mine = per_client_[k][client];
  if (mine >= caps[k][1]) {
    if (mine == 0) per_client_[k].erase(client);
    return {grpc::StatusCode::RESOURCE_EXHAUSTED,
            strprintf("%u %s already open from %s, the most per client (%s); close one and "
                      "retry",
                      caps[k][1], kInfo[k].what, client.c_str(), kInfo[k].client_flag)};
  }
  if (total_[k] >= caps[k][0]) {
    if (mine == 0) per_client_[k].erase(client);
    return {grpc::StatusCode::RESOURCE_EXHAUSTED,
            strprintf("%u %s already open, the most the daemon allows (%s); retry later",
                      caps[k][0], kInfo[k].what, kInfo[k].total_flag)};
  }
  ++mine;
  ++total_[k];
  slot->release();
  slot->owner_ = this;
  slot->kind_ = kind;
  slot->client_ = client;
  return grpc::Status::OK;
}

uint32_t StreamSlots::open(StreamKind kind) const {
  std::lock_guard<std::mutex> lock(mu_);
  return total_[static_cast<int>(kind)];
}

void StreamSlots::release(StreamKind kind, const std::string& client) {
  const int k = static_cast<int>(kind);
  std::lock_guard<std::mutex> lock(mu_);
  --total_[k];
  auto it = per_client_[k].find(client);
  if (it != per_client_[k].end() && --it->second == 0) per_client_[k].erase(it);
}

}  // namespace luxel::service
