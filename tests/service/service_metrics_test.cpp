// The daemon's Prometheus endpoint (--metrics-listen), scraped with a plain
// HTTP GET over a socket during a bake and after it. Every expected value
// comes from somewhere else than the metrics code: file sizes on disk, the
// bake's own record (GetBake), the RPCs this test made, the artifact bytes
// it downloaded.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <thread>

#include "daemon_harness.h"

namespace luxel::test {
namespace {

namespace fs = std::filesystem;
using Labels = std::map<std::string, std::string>;

int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t n = sizeof a;
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
  close(fd);
  return ntohs(a.sin_port);
}

// GET /metrics over a plain socket; the body ("" on any failure).
std::string http_get_metrics(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    close(fd);
    return "";
  }
  const std::string req = "GET /metrics HTTP/1.0\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
  if (write(fd, req.data(), req.size()) != static_cast<ssize_t>(req.size())) {
    close(fd);
    return "";
  }
  std::string resp;
  char buf[4096];
  for (ssize_t n; (n = read(fd, buf, sizeof buf)) > 0;) resp.append(buf, static_cast<size_t>(n));
  close(fd);
  const size_t body = resp.find("\r\n\r\n");
  if (resp.rfind("HTTP/1.", 0) != 0 || resp.find(" 200 ") == std::string::npos ||
      body == std::string::npos)
    return "";
  return resp.substr(body + 4);
}

// The text exposition format parsed into "name{k=v,...}" (labels sorted) ->
// value, written independently of prometheus-cpp's serializer.
class Scrape {
 public:
  explicit Scrape(const std::string& text) : text_(text) {
    size_t pos = 0;
    while (pos < text.size()) {
      size_t end = text.find('\n', pos);
      if (end == std::string::npos) end = text.size();
      const std::string line = text.substr(pos, end - pos);
      pos = end + 1;
      if (line.empty() || line[0] == '#') continue;
      const size_t space = line.rfind(' ');
      const std::string series = line.substr(0, space);
      Labels labels;
      std::string name = series;
      if (size_t brace = series.find('{'); brace != std::string::npos) {
        name = series.substr(0, brace);
        size_t i = brace + 1;
        while (i < series.size() && series[i] != '}') {
          const size_t eq = series.find('=', i);
          const size_t close = series.find('"', eq + 2);
          labels[series.substr(i, eq - i)] = series.substr(eq + 2, close - eq - 2);
          i = close + 1;
          if (i < series.size() && series[i] == ',') ++i;
        }
      }
      values_[key(name, labels)] = std::stod(line.substr(space + 1));
    }
  }
  std::optional<double> get(const std::string& name, const Labels& labels = {}) const {
    auto it = values_.find(key(name, labels));
    if (it == values_.end()) return std::nullopt;
    return it->second;
  }
  double value(const std::string& name, const Labels& labels = {}) const {
    return get(name, labels).value_or(-1);
  }
  const std::string& text() const { return text_; }

 private:
  static std::string key(const std::string& name, const Labels& labels) {
    std::string k = name + "{";
    for (const auto& [l, v] : labels) k += l + "=" + v + ",";
    return k + "}";
  }
  std::string text_;
  std::map<std::string, double> values_;
};

class ServiceMetrics : public ::testing::Test {
 protected:
  void SetUp() override {
    port_ = free_port();
    daemon_ = std::make_unique<Daemon>(
        dir_.path() + "/data",
        std::vector<std::string>{"--metrics-listen", "127.0.0.1:" + std::to_string(port_),
                                 "--checkpoint-interval", "0"});
  }
  void TearDown() override { EXPECT_EQ(daemon_->stop(SIGTERM), 0) << daemon_->log(); }
  Scrape scrape() const {
    const std::string body = http_get_metrics(port_);
    EXPECT_FALSE(body.empty()) << "no /metrics answer on port " << port_;
    return Scrape(body);
  }
  grpc::Status submit(const std::string& scene, const v1::BakeSettings& s, v1::BakeInfo* out) {
    v1::SubmitBakeRequest req;
    req.set_scene_id(scene);
    *req.mutable_settings() = s;
    auto ctx = daemon_->context();
    return daemon_->stub()->SubmitBake(ctx.get(), req, out);
  }
  v1::BakeInfo get_bake(const std::string& id) {
    v1::GetBakeRequest req;
    req.set_bake_id(id);
    v1::BakeInfo info;
    auto ctx = daemon_->context();
    EXPECT_TRUE(daemon_->stub()->GetBake(ctx.get(), req, &info).ok());
    return info;
  }
  TempDir dir_;
  int port_ = 0;
  std::unique_ptr<Daemon> daemon_;
};

TEST_F(ServiceMetrics, ScrapeDuringAndAfterABakeShowsRealFigures) {
  const Scrape idle = scrape();
  EXPECT_EQ(idle.value("luxel_upload_bytes_total"), 0) << idle.text();
  EXPECT_EQ(idle.value("luxel_paths_traced_total"), 0);
  EXPECT_EQ(idle.value("luxel_queue_depth"), 0);
  EXPECT_EQ(idle.value("luxel_bakes", {{"state", "running"}}), 0);
  EXPECT_FALSE(idle.get("luxel_rpc_requests_total", {{"method", "SubmitBake"}, {"code", "OK"}}));

  // Upload: the counter equals the bytes of the two files on disk.
  const std::string gltf = read_file(LUXEL_SCENES_DIR "/cornell_box.gltf");
  const std::string bin = read_file(LUXEL_SCENES_DIR "/cornell_box.bin");
  v1::SceneInfo scene;
  ASSERT_TRUE(upload_scene(*daemon_, "cornell_box.gltf", v1::SCENE_FORMAT_GLTF, gltf,
                           {{"cornell_box.bin", bin}}, &scene)
                  .ok());
  const double uploaded = static_cast<double>(fs::file_size(LUXEL_SCENES_DIR "/cornell_box.gltf") +
                                              fs::file_size(LUXEL_SCENES_DIR "/cornell_box.bin"));

  // A timed bake (one worker) and a second one queued behind it.
  v1::BakeSettings timed = small_settings(0, 32);
  timed.set_time_budget_s(4);
  v1::BakeInfo running, queued;
  ASSERT_TRUE(submit(scene.scene_id(), timed, &running).ok());
  ASSERT_TRUE(submit(scene.scene_id(), small_settings(4, 16), &queued).ok());
  // A failing call: an unknown (well-formed) bake id.
  {
    v1::GetBakeRequest req;
    req.set_bake_id(std::string(32, 'a'));
    v1::BakeInfo info;
    auto ctx = daemon_->context();
    ASSERT_EQ(daemon_->stub()->GetBake(ctx.get(), req, &info).error_code(),
              grpc::StatusCode::NOT_FOUND);
  }

  // A watcher holds a stream open while we scrape.
  v1::WatchBakeRequest watch_req;
  watch_req.set_bake_id(running.bake_id());
  auto watch_ctx = daemon_->context(std::chrono::seconds(60));
  auto stub = daemon_->stub();
  auto watch = stub->WatchBake(watch_ctx.get(), watch_req);
  v1::BakeEvent event;
  ASSERT_TRUE(watch->Read(&event));

  // During: wait until the bake has reported some progress (the first bake
  // of a fresh cache builds its kernels first: allow for a slow machine).
  std::optional<Scrape> during;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(90);
  while (std::chrono::steady_clock::now() < deadline) {
    Scrape s = scrape();
    if (s.value("luxel_bakes", {{"state", "running"}}) == 1 &&
        s.value("luxel_paths_traced_total") > 0) {
      during = s;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE(during) << scrape().text();
  EXPECT_EQ(get_bake(running.bake_id()).state(), v1::BAKE_STATE_RUNNING);
  EXPECT_EQ(during->value("luxel_queue_depth"), 1) << during->text();
  EXPECT_EQ(during->value("luxel_bakes", {{"state", "queued"}}), 1);
  EXPECT_EQ(during->value("luxel_bakes", {{"state", "succeeded"}}), 0);
  EXPECT_GT(during->value("luxel_paths_per_second"), 0);
  EXPECT_GT(during->value("luxel_device_memory_bytes"), 0);
  EXPECT_EQ(during->value("luxel_active_streams", {{"kind", "watchers"}}), 1);
  EXPECT_EQ(during->value("luxel_active_streams", {{"kind", "uploads"}}), 0);
  EXPECT_EQ(during->value("luxel_upload_bytes_total"), uploaded);
  EXPECT_EQ(during->value("luxel_rpc_requests_total", {{"method", "SubmitBake"}, {"code", "OK"}}),
            2);
  EXPECT_EQ(during->value("luxel_rpc_requests_total", {{"method", "UploadScene"}, {"code", "OK"}}),
            1);
  EXPECT_EQ(
      during->value("luxel_rpc_requests_total", {{"method", "GetBake"}, {"code", "NOT_FOUND"}}), 1);
  EXPECT_EQ(
      during->value("luxel_rpc_duration_seconds_count", {{"method", "SubmitBake"}, {"code", "OK"}}),
      2);

  while (watch->Read(&event)) {
  }
  EXPECT_TRUE(watch->Finish().ok());
  const v1::BakeInfo done = wait_for_bake(*daemon_, running.bake_id(), is_finished);
  ASSERT_EQ(done.state(), v1::BAKE_STATE_SUCCEEDED);
  const v1::BakeInfo second = wait_for_bake(*daemon_, queued.bake_id(), is_finished);
  ASSERT_EQ(second.state(), v1::BAKE_STATE_SUCCEEDED);
  std::string bytes, sha;
  uint64_t total = 0;
  ASSERT_TRUE(download(*daemon_, running.bake_id(), "irradiance.exr", &bytes, &sha, &total).ok());

  const Scrape after = scrape();
  // Paths: the counter is the sum of what the two bakes report they traced.
  EXPECT_EQ(after.value("luxel_paths_traced_total"),
            static_cast<double>(done.progress().paths() + second.progress().paths()))
      << after.text();
  EXPECT_EQ(after.value("luxel_queue_depth"), 0);
  EXPECT_EQ(after.value("luxel_bakes", {{"state", "running"}}), 0);
  EXPECT_EQ(after.value("luxel_bakes", {{"state", "succeeded"}}), 2);
  EXPECT_EQ(after.value("luxel_paths_per_second"), 0);
  EXPECT_EQ(after.value("luxel_device_memory_bytes"), 0);
  EXPECT_EQ(after.value("luxel_active_streams", {{"kind", "watchers"}}), 0);
  EXPECT_EQ(after.value("luxel_active_streams", {{"kind", "downloads"}}), 0);
  EXPECT_EQ(after.value("luxel_download_bytes_total"), static_cast<double>(bytes.size()));
  EXPECT_EQ(after.value("luxel_upload_bytes_total"), uploaded);
  // Durations by outcome: one bake stopped on time, one on samples; the
  // histogram's sum is the bakes' own seconds.
  EXPECT_EQ(after.value("luxel_bake_duration_seconds_count", {{"outcome", "time"}}), 1);
  EXPECT_EQ(after.value("luxel_bake_duration_seconds_count", {{"outcome", "samples"}}), 1);
  EXPECT_NEAR(after.value("luxel_bake_duration_seconds_sum", {{"outcome", "time"}}),
              done.progress().elapsed_s(), 1e-6);
  EXPECT_EQ(
      after.value("luxel_bake_duration_seconds_bucket", {{"outcome", "time"}, {"le", "+Inf"}}), 1);
  EXPECT_EQ(after.value("luxel_rpc_requests_total", {{"method", "WatchBake"}, {"code", "OK"}}), 1);
  EXPECT_EQ(after.value("luxel_rpc_requests_total", {{"method", "DownloadResult"}, {"code", "OK"}}),
            1);
  // No series for a code that never happened (the parser finds absence).
  EXPECT_FALSE(
      after.get("luxel_rpc_requests_total", {{"method", "SubmitBake"}, {"code", "NOT_FOUND"}}));
}

// Bad --metrics-listen values stop the daemon at startup with a clear error.
TEST(ServiceMetricsFlags, BadAddressIsAStartupError) {
  TempDir dir;
  auto run = [&](const std::string& address) {
    const std::string cmd = std::string(LUXELD_PATH) + " --data-dir " + dir.path() +
                            "/data --metrics-listen '" + address + "' 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    char buf[512];
    for (size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
    const int status = pclose(p);
    return std::make_pair(WIFEXITED(status) ? WEXITSTATUS(status) : -1, out);
  };
  for (const std::string bad : {"9464", "localhost:9464", "127.0.0.1:70000", "127.0.0.1:", ":9464",
                                "1.2.3:80", "127.0.0.1:http"}) {
    auto [code, out] = run(bad);
    EXPECT_EQ(code, 2) << bad << ": " << out;
    EXPECT_NE(out.find("--metrics-listen: "), std::string::npos) << bad << ": " << out;
  }
  // A port already taken: the daemon gives up (exit 1) and says why.
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(listen(fd, 1), 0);
  socklen_t n = sizeof a;
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
  auto [code, out] = run("127.0.0.1:" + std::to_string(ntohs(a.sin_port)));
  close(fd);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("--metrics-listen: cannot listen"), std::string::npos) << out;
}

}  // namespace
}  // namespace luxel::test
