// `luxel upload SCENE [--name N]` and the upload stream it shares with bake.
#include "remote/upload.h"

#include <cstdio>
#include <vector>

#include "commands.h"
#include "remote/output.h"

namespace luxel::cli::remote {
namespace {

// Sends one file in chunks. A chunk never spans two files, so the daemon can
// cut the stream by the sizes in the header either way.
grpc::Status send_file(grpc::ClientWriter<luxel::v1::UploadSceneRequest>& writer,
                       const SceneFile& file, bool& stream_broken) {
  FILE* f = std::fopen(file.path.c_str(), "rb");
  if (!f) return {grpc::StatusCode::NOT_FOUND, "cannot open '" + file.path + "'"};
  std::vector<char> buf(kUploadChunkBytes);
  luxel::v1::UploadSceneRequest req;
  uint64_t sent = 0;
  size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), f)) > 0) {
    req.set_chunk(buf.data(), n);
    if (!writer.Write(req)) {
      stream_broken = true;  // the daemon ended the call; Finish() says why
      break;
    }
    sent += n;
  }
  std::fclose(f);
  if (!stream_broken && sent != file.size)
    return {grpc::StatusCode::ABORTED,
            "'" + file.path + "' changed while it was being uploaded (size differs from its hash)"};
  return grpc::Status::OK;
}

}  // namespace

grpc::Status upload_scene(Connection& conn, const SceneFiles& files, const std::string& name,
                          luxel::v1::SceneInfo& info) {
  grpc::ClientContext ctx;
  conn.prepare_stream(ctx);
  auto writer = conn.stub().UploadScene(&ctx, &info);
  luxel::v1::UploadSceneRequest header;
  *header.mutable_header() = upload_header(files, name);
  bool broken = !writer->Write(header);
  grpc::Status local = grpc::Status::OK;
  if (!broken) local = send_file(*writer, files.main, broken);
  for (size_t i = 0; local.ok() && !broken && i < files.resources.size(); ++i)
    local = send_file(*writer, files.resources[i], broken);
  if (!local.ok()) {
    // Abandon the call: the daemon sees a cancelled stream and stores nothing.
    ctx.TryCancel();
    (void)writer->Finish();
    return local;
  }
  if (!broken) writer->WritesDone();
  return writer->Finish();
}

grpc::Status ensure_scene(Connection& conn, const SceneFiles& files, const std::string& name,
                          luxel::v1::SceneInfo& info, bool& uploaded) {
  uploaded = false;
  grpc::ClientContext ctx;
  conn.prepare_unary(ctx);
  luxel::v1::GetSceneRequest req;
  req.set_scene_id(scene_id(files));
  grpc::Status st = conn.stub().GetScene(&ctx, req, &info);
  if (st.error_code() != grpc::StatusCode::NOT_FOUND) return st;
  uploaded = true;
  return upload_scene(conn, files, name, info);
}

}  // namespace luxel::cli::remote

namespace luxel::cli {

int run_upload(const std::vector<std::string>& args) {
  using namespace remote;
  static const char* kUsage =
      "usage: luxel upload SCENE [--name NAME] [connection options]\n"
      "  uploads a .gltf (with the buffers and images it references) or a .glb;\n"
      "  prints the scene id, statistics and import warnings\n"
      "  --name NAME           display name (default: the file name)\n";
  ConnectionOptions copt = default_connection_options();
  std::string scene, name;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& k = args[i];
    const OptionMatch m = take_connection_option("upload", args, i, copt);
    if (m == OptionMatch::kError) return kExitUsage;
    if (m == OptionMatch::kTaken) continue;
    if (k == "--help" || k == "-h") {
      std::printf("%s%s", kUsage, kConnectionUsage);
      return kExitOk;
    }
    if (k == "--name" && i + 1 < args.size())
      name = args[++i];
    else if (!k.empty() && k[0] == '-') {
      std::fprintf(stderr, "luxel upload: unknown option or missing value '%s'\n%s", k.c_str(),
                   kUsage);
      return kExitUsage;
    } else if (scene.empty())
      scene = k;
    else {
      std::fprintf(stderr, "luxel upload: unexpected argument '%s'\n", k.c_str());
      return kExitUsage;
    }
  }
  if (scene.empty()) {
    std::fprintf(stderr, "luxel upload: a SCENE file is required\n%s", kUsage);
    return kExitUsage;
  }
  SceneFiles files;
  if (auto st = collect_scene_files(scene, files); !st.ok()) {
    std::fprintf(stderr, "luxel upload: %s\n", st.error_message().c_str());
    return st.error_code() == grpc::StatusCode::INVALID_ARGUMENT ? kExitUsage : kExitRuntime;
  }
  auto conn = Connection::open("upload", copt);
  if (!conn) return kExitUsage;
  luxel::v1::SceneInfo info;
  if (auto st = upload_scene(*conn, files, name, info); !st.ok()) return conn->fail("upload", st);
  if (copt.json) {
    print_json_line(to_json(info));
  } else {
    uint64_t bytes = files.main.size;
    for (const auto& r : files.resources) bytes += r.size;
    std::printf("uploaded   %s + %zu resources, %llu bytes\n", scene.c_str(),
                files.resources.size(), static_cast<unsigned long long>(bytes));
    print_scene_info(info);
  }
  return kExitOk;
}

}  // namespace luxel::cli
