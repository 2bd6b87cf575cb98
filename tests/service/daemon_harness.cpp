#include "daemon_harness.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <openssl/evp.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace luxel::test {

namespace fs = std::filesystem;

namespace {

// Binds port 0 to learn a free port; luxeld binds it right after (the small
// window in between is harmless on a test machine).
int free_loopback_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
    throw std::runtime_error("bind");
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  close(fd);
  return ntohs(addr.sin_port);
}

}  // namespace

Daemon::Daemon(std::string data_dir, std::vector<std::string> extra_args, std::string token)
    : data_dir_(std::move(data_dir)), token_(std::move(token)) {
  address_ = "127.0.0.1:" + std::to_string(free_loopback_port());
  log_path_ = data_dir_ + ".luxeld.log";
  std::vector<std::string> args = {LUXELD_PATH, "--listen", address_, "--data-dir", data_dir_};
  args.insert(args.end(), extra_args.begin(), extra_args.end());
  pid_ = fork();
  if (pid_ == 0) {
    // The daemon takes its token from the environment (never from argv).
    if (!token_.empty()) setenv("LUXELD_TOKEN", token_.c_str(), 1);
    const int fd = open(log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) dup2(fd, 2);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  auto channel = grpc::CreateChannel(address_, grpc::InsecureChannelCredentials());
  if (!channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(20)))
    throw std::runtime_error("luxeld did not start; log:\n" + log());
}

Daemon::~Daemon() {
  if (pid_ > 0) stop(SIGKILL);
}

int Daemon::stop(int sig, std::chrono::seconds timeout) {
  if (pid_ <= 0) return -1;
  kill(pid_, sig);
  return wait_exit(timeout);
}

void Daemon::signal(int sig) const {
  if (pid_ > 0) kill(pid_, sig);
}

int Daemon::wait_exit(std::chrono::milliseconds timeout) {
  if (pid_ <= 0) return -1;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    int status = 0;
    const pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      pid_ = -1;
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid_, SIGKILL);
      waitpid(pid_, &status, 0);
      pid_ = -1;
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

std::unique_ptr<v1::Luxel::Stub> Daemon::stub() const {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(64 << 20);
  return v1::Luxel::NewStub(
      grpc::CreateCustomChannel(address_, grpc::InsecureChannelCredentials(), args));
}

std::unique_ptr<grpc::ClientContext> Daemon::context(std::chrono::seconds deadline) const {
  auto ctx = std::make_unique<grpc::ClientContext>();
  if (!token_.empty()) ctx->AddMetadata("authorization", "Bearer " + token_);
  ctx->set_deadline(std::chrono::system_clock::now() + deadline);
  return ctx;
}

std::string Daemon::log() const {
  return read_file(log_path_);
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string sha256_hex(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest, &n, EVP_sha256(), nullptr);
  std::string hex;
  char buf[3];
  for (unsigned i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof buf, "%02x", digest[i]);
    hex += buf;
  }
  return hex;
}

grpc::Status upload_scene(const Daemon& d, const std::string& name, v1::SceneFormat format,
                          const std::string& main_bytes, const std::vector<Resource>& resources,
                          v1::SceneInfo* out, const UploadOptions& options) {
  auto stub = d.stub();
  auto ctx = d.context();
  auto writer = stub->UploadScene(ctx.get(), out);
  v1::UploadSceneRequest req;
  auto* h = req.mutable_header();
  h->set_name(name);
  h->set_format(format);
  h->set_total_size(options.size_override ? options.size_override : main_bytes.size());
  h->set_sha256(options.sha256_override.empty() ? sha256_hex(main_bytes) : options.sha256_override);
  std::string payload = main_bytes;
  for (const auto& r : resources) {
    auto* rh = h->add_resources();
    rh->set_uri(r.uri);
    rh->set_size(r.bytes.size());
    rh->set_sha256(sha256_hex(r.bytes));
    payload += r.bytes;
  }
  if (options.truncate_after >= 0) payload.resize(static_cast<size_t>(options.truncate_after));
  bool ok = writer->Write(req);
  for (size_t pos = 0; ok && pos < payload.size(); pos += options.chunk_bytes) {
    v1::UploadSceneRequest chunk;
    chunk.set_chunk(payload.substr(pos, options.chunk_bytes));
    ok = writer->Write(chunk);
  }
  writer->WritesDone();
  return writer->Finish();
}

bool is_finished(const v1::BakeInfo& info) {
  return info.state() == v1::BAKE_STATE_SUCCEEDED || info.state() == v1::BAKE_STATE_FAILED ||
         info.state() == v1::BAKE_STATE_CANCELLED;
}

v1::BakeInfo wait_for_bake(const Daemon& d, const std::string& bake_id,
                           bool (*done)(const v1::BakeInfo&), std::chrono::seconds timeout) {
  auto stub = d.stub();
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  v1::BakeInfo info;
  while (std::chrono::steady_clock::now() < deadline) {
    v1::GetBakeRequest req;
    req.set_bake_id(bake_id);
    auto ctx = d.context();
    if (stub->GetBake(ctx.get(), req, &info).ok() && done(info)) return info;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return info;
}

grpc::Status download(const Daemon& d, const std::string& bake_id, const std::string& artifact,
                      std::string* bytes, std::string* sha256, uint64_t* total_size) {
  auto stub = d.stub();
  auto ctx = d.context();
  v1::DownloadResultRequest req;
  req.set_bake_id(bake_id);
  req.set_artifact(artifact);
  auto reader = stub->DownloadResult(ctx.get(), req);
  v1::DownloadResultResponse msg;
  bytes->clear();
  sha256->clear();
  bool first = true;
  while (reader->Read(&msg)) {
    if (first) *total_size = msg.total_size();
    first = false;
    if (!sha256->empty()) *sha256 = "sha256 was not in the last message";
    *bytes += msg.chunk();
    if (!msg.sha256().empty()) *sha256 = msg.sha256();
  }
  return reader->Finish();
}

grpc::Status raw_unary(const Daemon& d, const std::string& method, const std::string& request,
                       std::string* response) {
  grpc::GenericStub stub(grpc::CreateChannel(d.address(), grpc::InsecureChannelCredentials()));
  auto ctx = d.context();
  grpc::Slice slice(request);
  grpc::ByteBuffer req(&slice, 1), resp;
  std::promise<grpc::Status> done;
  stub.UnaryCall(ctx.get(), method, grpc::StubOptions(), &req, &resp,
                 [&](grpc::Status st) { done.set_value(std::move(st)); });
  grpc::Status st = done.get_future().get();
  std::vector<grpc::Slice> slices;
  response->clear();
  if (st.ok() && resp.Dump(&slices).ok())
    for (const auto& s : slices)
      response->append(reinterpret_cast<const char*>(s.begin()), s.size());
  return st;
}

grpc::Status raw_bidi_once(const Daemon& d, const std::string& method, const std::string& request,
                           std::string* response) {
  grpc::GenericStub stub(grpc::CreateChannel(d.address(), grpc::InsecureChannelCredentials()));
  auto ctx = d.context();
  grpc::CompletionQueue cq;
  auto call = stub.PrepareCall(ctx.get(), method, &cq);
  void* tag = nullptr;
  bool ok = false;
  auto step = [&](intptr_t expected) {
    return cq.Next(&tag, &ok) && reinterpret_cast<intptr_t>(tag) == expected && ok;
  };
  call->StartCall(reinterpret_cast<void*>(1));
  grpc::Slice slice(request);
  grpc::ByteBuffer req(&slice, 1), resp;
  grpc::Status st;
  response->clear();
  if (step(1)) {
    call->Write(req, reinterpret_cast<void*>(2));
    if (step(2)) {
      call->Read(&resp, reinterpret_cast<void*>(3));
      std::vector<grpc::Slice> slices;
      if (step(3) && resp.Dump(&slices).ok())
        for (const auto& s : slices)
          response->append(reinterpret_cast<const char*>(s.begin()), s.size());
    }
  }
  call->WritesDone(reinterpret_cast<void*>(4));
  cq.Next(&tag, &ok);
  call->Finish(&st, reinterpret_cast<void*>(5));
  while (cq.Next(&tag, &ok) && reinterpret_cast<intptr_t>(tag) != 5) {
  }
  cq.Shutdown();
  while (cq.Next(&tag, &ok)) {
  }
  return st;
}

v1::BakeInfo submit_bake(const Daemon& d, const std::string& scene_id, const v1::BakeSettings& s) {
  v1::SubmitBakeRequest req;
  req.set_scene_id(scene_id);
  *req.mutable_settings() = s;
  v1::BakeInfo info;
  auto ctx = d.context();
  auto st = d.stub()->SubmitBake(ctx.get(), req, &info);
  EXPECT_TRUE(st.ok()) << st.error_message();
  return info;
}

v1::BakeInfo cancel_bake(const Daemon& d, const std::string& bake_id) {
  v1::CancelBakeRequest req;
  req.set_bake_id(bake_id);
  v1::BakeInfo info;
  auto ctx = d.context();
  auto st = d.stub()->CancelBake(ctx.get(), req, &info);
  EXPECT_TRUE(st.ok()) << st.error_message();
  return info;
}

v1::BakeSettings small_settings(uint32_t spp, uint32_t resolution) {
  v1::BakeSettings s;
  s.set_resolution(resolution);
  s.set_samples_per_texel(spp);
  s.set_max_bounces(2);
  s.set_paths_per_iteration(16384);
  s.set_snapshot_interval_s(0.1);
  s.set_progress_interval_s(0.1);
  s.set_snapshot_max_side(32);
  return s;
}

std::string upload_cornell(const Daemon& d) {
  v1::SceneInfo info;
  auto st = upload_scene(
      d, "cornell_box.gltf", v1::SCENE_FORMAT_GLTF, read_file(LUXEL_SCENES_DIR "/cornell_box.gltf"),
      {{"cornell_box.bin", read_file(LUXEL_SCENES_DIR "/cornell_box.bin")}}, &info);
  EXPECT_TRUE(st.ok()) << st.error_message();
  return info.scene_id();
}

}  // namespace luxel::test
