// Stream caps without a server: the client identity taken from gRPC peer
// strings, per-client and total accounting, slots freed on destruction and
// move, and the flags that set the caps and upload deadlines.
#include "service/stream_limits.h"

#include <gtest/gtest.h>

#include "service/daemon_config.h"

namespace luxel::service {
namespace {

TEST(PeerHost, DropsTheSchemeAndThePort) {
  EXPECT_EQ(peer_host("ipv4:10.0.0.7:5123"), "10.0.0.7");
  EXPECT_EQ(peer_host("ipv6:[::1]:5123"), "[::1]");
  EXPECT_EQ(peer_host("ipv6:[fe80::1%eth0]:80"), "[fe80::1%eth0]");
  EXPECT_EQ(peer_host("unix:/tmp/luxel.sock"), "unix:/tmp/luxel.sock");
  // Two connections from one host are one client.
  EXPECT_EQ(peer_host("ipv4:127.0.0.1:40000"), peer_host("ipv4:127.0.0.1:40001"));
}

TEST(StreamSlots, PerClientCapComesFirstAndNamesItsFlag) {
  StreamCaps caps;
  caps.max_watchers = 3;
  caps.max_watchers_per_client = 2;
  StreamSlots slots(caps);
  StreamSlot a, b, c, d;
  ASSERT_TRUE(slots.acquire(StreamKind::kWatch, "h1", &a).ok());
  ASSERT_TRUE(slots.acquire(StreamKind::kWatch, "h1", &b).ok());
  grpc::Status st = slots.acquire(StreamKind::kWatch, "h1", &c);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(st.error_message().find("--max-watchers-per-client"), std::string::npos)
      << st.error_message();
  EXPECT_FALSE(c.held());
  // Another host still gets the last slot of the total ...
  ASSERT_TRUE(slots.acquire(StreamKind::kWatch, "h2", &c).ok());
  // ... and then the total cap refuses everyone.
  st = slots.acquire(StreamKind::kWatch, "h3", &d);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(st.error_message().find("(--max-watchers)"), std::string::npos) << st.error_message();
  EXPECT_EQ(slots.open(StreamKind::kWatch), 3u);
  // Other kinds are counted apart.
  StreamSlot up;
  EXPECT_TRUE(slots.acquire(StreamKind::kUpload, "h1", &up).ok());
}

TEST(StreamSlots, SlotsAreFreedOnDestructionAndMove) {
  StreamCaps caps;
  caps.max_uploads = 1;
  StreamSlots slots(caps);
  {
    StreamSlot a;
    ASSERT_TRUE(slots.acquire(StreamKind::kUpload, "h", &a).ok());
    StreamSlot moved = std::move(a);
    EXPECT_FALSE(a.held());
    EXPECT_TRUE(moved.held());
    EXPECT_EQ(slots.open(StreamKind::kUpload), 1u);
  }
  EXPECT_EQ(slots.open(StreamKind::kUpload), 0u);
  StreamSlot again;
  EXPECT_TRUE(slots.acquire(StreamKind::kUpload, "h", &again).ok());
  again.release();
  again.release();  // idempotent
  EXPECT_EQ(slots.open(StreamKind::kUpload), 0u);
}

TEST(DaemonConfig, StreamFlags) {
  auto c = parse_daemon_args({"--data-dir", "/tmp/x", "--max-uploads", "5",
                              "--max-watchers-per-client", "7", "--max-downloads", "9",
                              "--upload-idle-timeout", "2.5", "--upload-timeout", "0"});
  ASSERT_TRUE(c) << c.status().to_string();
  EXPECT_EQ(c->streams.max_uploads, 5u);
  EXPECT_EQ(c->streams.max_uploads_per_client, StreamCaps{}.max_uploads_per_client);
  EXPECT_EQ(c->streams.max_watchers_per_client, 7u);
  EXPECT_EQ(c->streams.max_downloads, 9u);
  EXPECT_EQ(c->upload_idle_timeout_s, 2.5);
  EXPECT_EQ(c->upload_timeout_s, 0.0);
  auto bad = parse_daemon_args({"--data-dir", "/tmp/x", "--max-watchers", "0"});
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.status().message().find("--max-watchers"), std::string::npos);
  bad = parse_daemon_args({"--data-dir", "/tmp/x", "--upload-idle-timeout", "0"});
  ASSERT_FALSE(bad);
}

}  // namespace
}  // namespace luxel::service
