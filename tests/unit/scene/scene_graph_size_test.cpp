// Large node graphs import completely and correctly: 100,000 nodes side by
// side and a chain 100,000 nodes deep (each the child of the one before),
// and the JSON nesting limit holds at its boundary. The import's time against
// the node count is measured by tests/bench/import_nodes.py, not here.
#include <gtest/gtest.h>

#include <string>

#include "scene/gltf_import.h"
#include "scene/gltf_load.h"

namespace luxel::scene {
namespace {

// One triangle (three vec3 positions, base64 in a data URI) used by every node.
constexpr const char* kTriangleAssets = R"("asset":{"version":"2.0"},
"buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAAAAAIA/"}],
"bufferViews":[{"buffer":0,"byteLength":36}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}])";

// n nodes with the triangle, each moved by dx along x; chain: node i + 1 is
// node i's child (one root), else every node is a root.
std::string node_graph(int n, bool chain, double dx) {
  std::string nodes;
  nodes.reserve(static_cast<size_t>(n) * 64);
  for (int i = 0; i < n; ++i) {
    if (i) nodes += ',';
    nodes += "{\"mesh\":0,\"translation\":[" + std::to_string(chain ? dx : dx * i) + ",0,0]";
    if (chain && i + 1 < n) nodes += ",\"children\":[" + std::to_string(i + 1) + "]";
    nodes += '}';
  }
  std::string roots;
  if (chain) {
    roots = "0";
  } else {
    for (int i = 0; i < n; ++i) roots += (i ? "," : "") + std::to_string(i);
  }
  return std::string("{") + kTriangleAssets + ",\"nodes\":[" + nodes +
         "],\"scenes\":[{\"nodes\":[" + roots + "]}],\"scene\":0}";
}

constexpr int kNodes = 100000;

TEST(SceneGraphSize, HundredThousandRootNodes) {
  auto r = import_gltf_memory(node_graph(kNodes, false, 0.5), "", "flat.gltf");
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  ASSERT_EQ(r->instances.size(), size_t{kNodes});
  // Every instance keeps its own node's translation.
  EXPECT_DOUBLE_EQ(r->instances.back().object_to_world.at(0, 3), 0.5 * (kNodes - 1));
  EXPECT_DOUBLE_EQ(r->instances[1].object_to_world.at(0, 3), 0.5);
}

TEST(SceneGraphSize, ChainOfHundredThousandNodes) {
  // Translations compose down the chain: node i sits at (i + 1) * dx.
  auto r = import_gltf_memory(node_graph(kNodes, true, 0.25), "", "chain.gltf");
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  ASSERT_EQ(r->instances.size(), size_t{kNodes});
  double deepest = 0;
  for (const Instance& in : r->instances) deepest = std::max(deepest, in.object_to_world.at(0, 3));
  EXPECT_DOUBLE_EQ(deepest, 0.25 * kNodes);
}

// A valid glTF whose extras hold an array nested `depth` levels deep overall
// (the top-level object counts as one).
std::string nested(int depth) {
  const int arrays = depth - 2;  // the document and the asset object
  return std::string("{\"asset\":{\"version\":\"2.0\",\"extras\":") + std::string(arrays, '[') +
         std::string(arrays, ']') + "}}";
}

TEST(SceneGraphSize, JsonNestingLimitAtItsBoundary) {
  auto at_limit = import_gltf_memory(nested(detail::kMaxJsonDepth), "", "deep.gltf");
  EXPECT_TRUE(at_limit.is_ok()) << at_limit.status().to_string();
  auto over = import_gltf_memory(nested(detail::kMaxJsonDepth + 1), "", "deeper.gltf");
  ASSERT_FALSE(over.is_ok());
  EXPECT_NE(over.status().message().find("'deeper.gltf'"), std::string::npos)
      << over.status().to_string();
  EXPECT_NE(over.status().message().find("nested deeper than 64 levels"), std::string::npos)
      << over.status().to_string();
}

}  // namespace
}  // namespace luxel::scene
