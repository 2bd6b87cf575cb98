// The CLI (client/remote/scene_files) and the daemon (SceneStore, SceneUpload)
// compute the same scene id and decode the same uris: the CLI's files go
// through a real SceneUpload and the stored id is the one the CLI predicted.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include "api/scene_files.h"
#include "scene/gltf_builder.h"
#include "service/scene_store.h"
#include "service/scene_upload.h"

namespace luxel::service {
namespace {

namespace remote = cli::remote;

std::string read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

test::GltfBuilder quad() {
  test::GltfBuilder b;
  const int mesh = b.add_mesh("quad", {b.triangles(test::kQuadPositions, test::kQuadIndices)});
  b.add_node({{"mesh", mesh}, {"name", "n"}});
  return b;
}

// Uploads `files` the way `luxel upload` does: the header, then the main
// file and every resource in header order.
Result<v1::SceneInfo> upload(SceneStore& store, const remote::SceneFiles& files) {
  auto up = SceneUpload::begin(store, remote::upload_header(files, ""), UploadLimits{});
  if (!up) return up.status();
  LUXEL_RETURN_IF_ERROR(up.value()->write(read(files.main.path)));
  for (const auto& r : files.resources) LUXEL_RETURN_IF_ERROR(up.value()->write(read(r.path)));
  return up.value()->finish();
}

TEST(SceneIdAgreement, CliAndDaemonComputeTheSameId) {
  test::TempDir src, data;
  test::GltfBuilder b = quad();
  src.write("my scene.bin", std::string(b.bin.begin(), b.bin.end()));
  src.write("b.gltf", b.gltf_external("my%20scene.bin"));  // a resource, escaped
  src.write("a.gltf", b.gltf_embedded());                  // no resources
  auto store = SceneStore::open(data.path());
  ASSERT_TRUE(store.is_ok()) << store.status().to_string();
  for (const char* name : {"a.gltf", "b.gltf"}) {
    remote::SceneFiles files;
    const grpc::Status st = remote::collect_scene_files(src.path() + "/" + name, files);
    ASSERT_TRUE(st.ok()) << st.error_message();
    const std::string cli_id = remote::scene_id(files);
    EXPECT_EQ(scene_id_of(remote::upload_header(files, "")), cli_id) << name;
    auto info = upload(*store.value(), files);
    ASSERT_TRUE(info.is_ok()) << name << ": " << info.status().to_string();
    EXPECT_EQ(info->scene_id(), cli_id) << name;
    EXPECT_FALSE(info->already_stored()) << name;
  }
}

TEST(SceneIdAgreement, MalformedEscapesAreRefusedOnBothSides) {
  test::TempDir src, data;
  test::GltfBuilder b = quad();
  src.write("scene.bin", std::string(b.bin.begin(), b.bin.end()));
  src.write("s.gltf", b.gltf_external("scene%zz.bin"));
  remote::SceneFiles files;
  const grpc::Status st = remote::collect_scene_files(src.path() + "/s.gltf", files);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("buffers[0]"), std::string::npos) << st.error_message();
  EXPECT_NE(st.error_message().find("'scene%zz.bin'"), std::string::npos) << st.error_message();

  auto store = SceneStore::open(data.path());
  ASSERT_TRUE(store.is_ok());
  for (const char* uri : {"scene%zz.bin", "scene%4", "scene.bin%00"}) {
    v1::SceneUploadHeader h;
    h.set_format(v1::SCENE_FORMAT_GLTF);
    h.set_total_size(10);
    h.set_sha256(std::string(64, 'a'));
    auto* r = h.add_resources();
    r->set_uri(uri);
    r->set_size(4);
    r->set_sha256(std::string(64, 'b'));
    auto up = SceneUpload::begin(*store.value(), h, UploadLimits{});
    ASSERT_FALSE(up.is_ok()) << uri;
    EXPECT_EQ(up.status().code(), StatusCode::kInvalidArgument) << uri;
    EXPECT_NE(up.status().message().find("header.resources.uri"), std::string::npos)
        << up.status().message();
    EXPECT_NE(up.status().message().find(std::string("'") + uri + "'"), std::string::npos)
        << up.status().message();
  }
}

}  // namespace
}  // namespace luxel::service
