// `luxel fetch BAKE --out DIR [--artifact NAME]...` and the download step of `luxel bake`.
#include "remote/fetch.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "api/file_hash.h"
#include "commands.h"
#include "common/status.h"
#include "remote/output.h"
#include "remote/watch.h"

namespace luxel::cli::remote {
namespace {

namespace fs = std::filesystem;

// The daemon names artifacts; a name must not climb out of --out.
bool is_plain_file_name(const std::string& name) {
  return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
         name.find('\\') == std::string::npos;
}

grpc::Status io_error(const std::string& what, const std::string& path) {
  return {grpc::StatusCode::INTERNAL, what + " '" + path + "': " + std::strerror(errno)};
}

// Writes to "<path>.part" and renames it over `path` once the content is
// verified, so `path` is always either absent, the old file or the new one.
class PartFile {
 public:
  explicit PartFile(std::string path) : path_(std::move(path)), part_(path_ + ".part") {}
  ~PartFile() {
    if (fd_ >= 0) ::close(fd_);
    if (!committed_) ::unlink(part_.c_str());
  }
  grpc::Status open() {
    fd_ = ::open(part_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    return fd_ < 0 ? io_error("cannot create", part_) : grpc::Status::OK;
  }
  grpc::Status write(const std::string& bytes) {
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return io_error("cannot write", part_);
      done += static_cast<size_t>(n);
    }
    return grpc::Status::OK;
  }
  grpc::Status commit() {
    if (::fsync(fd_) != 0) return io_error("cannot sync", part_);
    ::close(fd_);
    fd_ = -1;
    if (::rename(part_.c_str(), path_.c_str()) != 0) return io_error("cannot rename to", path_);
    committed_ = true;
    const std::string dir = fs::path(path_).parent_path().string();
    if (int dfd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY); dfd >= 0) {
      ::fsync(dfd);  // the rename itself survives a crash
      ::close(dfd);
    }
    return grpc::Status::OK;
  }

 private:
  std::string path_, part_;
  int fd_ = -1;
  bool committed_ = false;
};

}  // namespace

grpc::Status download_artifact(Connection& conn, const std::string& bake_id,
                               const std::string& name, const std::string& out_dir,
                               FetchedArtifact& out) {
  if (!is_plain_file_name(name))
    return {grpc::StatusCode::INVALID_ARGUMENT, "artifact name '" + name + "' is not a file name"};
  out = FetchedArtifact{name, (fs::path(out_dir) / name).string(), 0, ""};
  PartFile file(out.path);
  if (auto st = file.open(); !st.ok()) return st;
  grpc::ClientContext ctx;
  conn.prepare_stream(ctx);
  luxel::v1::DownloadResultRequest req;
  req.set_bake_id(bake_id);
  req.set_artifact(name);
  auto reader = conn.stub().DownloadResult(&ctx, req);
  luxel::v1::DownloadResultResponse msg;
  Sha256 hasher;
  uint64_t expected_size = 0;
  bool first = true;
  std::string server_sha;
  while (reader->Read(&msg)) {
    if (first) expected_size = msg.total_size();
    first = false;
    if (!msg.chunk().empty()) {
      if (auto st = file.write(msg.chunk()); !st.ok()) {
        ctx.TryCancel();
        (void)reader->Finish();
        return st;
      }
      hasher.update(msg.chunk().data(), msg.chunk().size());
      out.size += msg.chunk().size();
    }
    if (!msg.sha256().empty()) server_sha = msg.sha256();
  }
  if (grpc::Status st = reader->Finish(); !st.ok()) return st;
  out.sha256 = hasher.hex_digest();
  const std::string where = "artifact '" + name + "' of bake " + bake_id;
  if (server_sha.empty())
    return {grpc::StatusCode::DATA_LOSS, where + ": the stream ended without a checksum"};
  if (expected_size != 0 && out.size != expected_size)
    return {grpc::StatusCode::DATA_LOSS,
            where + strprintf(": received %llu bytes, expected %llu",
                              static_cast<unsigned long long>(out.size),
                              static_cast<unsigned long long>(expected_size))};
  if (server_sha != out.sha256)
    return {grpc::StatusCode::DATA_LOSS,
            where + ": sha256 " + out.sha256 + " does not match the daemon's " + server_sha};
  return file.commit();
}

grpc::Status download_artifacts(Connection& conn, const luxel::v1::BakeInfo& info,
                                const std::vector<std::string>& names, const std::string& out_dir,
                                bool json) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec)
    return {grpc::StatusCode::INVALID_ARGUMENT,
            "cannot create --out folder '" + out_dir + "': " + ec.message()};
  std::vector<std::string> wanted = names;
  if (wanted.empty()) wanted.assign(info.artifacts().begin(), info.artifacts().end());
  if (wanted.empty())
    return {grpc::StatusCode::NOT_FOUND, "bake " + info.bake_id() + " lists no artifacts"};
  for (const std::string& name : wanted) {
    FetchedArtifact a;
    if (auto st = download_artifact(conn, info.bake_id(), name, out_dir, a); !st.ok()) return st;
    if (json) {
      print_json_line({{"type", "artifact"},
                       {"bake_id", info.bake_id()},
                       {"name", a.name},
                       {"path", a.path},
                       {"size", a.size},
                       {"sha256", a.sha256}});
    } else {
      std::printf("wrote      %s (%llu bytes, sha256 %.16s… verified)\n", a.path.c_str(),
                  static_cast<unsigned long long>(a.size), a.sha256.c_str());
    }
  }
  return grpc::Status::OK;
}

}  // namespace luxel::cli::remote

namespace luxel::cli {

int run_fetch(const std::vector<std::string>& args) {
  using namespace remote;
  static const char* kUsage =
      "usage: luxel fetch BAKE --out DIR [--artifact NAME]... [connection options]\n"
      "  downloads the artifacts of a finished bake (all, or the named ones) into DIR,\n"
      "  verifying each against the daemon's sha256\n";
  ConnectionOptions copt = default_connection_options();
  std::string bake_id, out;
  std::vector<std::string> names;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& k = args[i];
    const OptionMatch m = take_connection_option("fetch", args, i, copt);
    if (m == OptionMatch::kError) return kExitUsage;
    if (m == OptionMatch::kTaken) continue;
    if (k == "--help" || k == "-h") {
      std::printf("%s%s", kUsage, kConnectionUsage);
      return kExitOk;
    }
    if (k == "--out" && i + 1 < args.size())
      out = args[++i];
    else if (k == "--artifact" && i + 1 < args.size())
      names.push_back(args[++i]);
    else if (!k.empty() && k[0] == '-') {
      std::fprintf(stderr, "luxel fetch: unknown option or missing value '%s'\n%s", k.c_str(),
                   kUsage);
      return kExitUsage;
    } else if (bake_id.empty())
      bake_id = k;
    else {
      std::fprintf(stderr, "luxel fetch: unexpected argument '%s'\n", k.c_str());
      return kExitUsage;
    }
  }
  if (bake_id.empty() || out.empty()) {
    std::fprintf(stderr, "luxel fetch: a BAKE id and --out DIR are required\n%s", kUsage);
    return kExitUsage;
  }
  auto conn = Connection::open("fetch", copt);
  if (!conn) return kExitUsage;
  luxel::v1::BakeInfo info;
  {
    grpc::ClientContext ctx;
    conn->prepare_unary(ctx);
    luxel::v1::GetBakeRequest req;
    req.set_bake_id(bake_id);
    if (auto st = conn->stub().GetBake(&ctx, req, &info); !st.ok()) return conn->fail("fetch", st);
  }
  if (info.state() != luxel::v1::BAKE_STATE_SUCCEEDED) {
    if (is_terminal(info.state())) return bake_outcome("fetch", info);
    std::fprintf(stderr,
                 "luxel fetch: bake %s is %s; its results exist once it SUCCEEDED "
                 "(luxel watch %s)\n",
                 bake_id.c_str(), state_name(info.state()).c_str(), bake_id.c_str());
    return kExitRuntime;
  }
  if (auto st = download_artifacts(*conn, info, names, out, copt.json); !st.ok())
    return conn->fail("fetch", st);
  return kExitOk;
}

}  // namespace luxel::cli
