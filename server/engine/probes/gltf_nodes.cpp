#include "probes/gltf_nodes.h"

#include <array>
#include <cstring>
#include <nlohmann/json.hpp>

namespace luxel::probes {
namespace {

using M = std::array<double, 16>;  // column-major, as glTF's matrix

M identity() {
  return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
}

M multiply(const M& a, const M& b) {
  M r{};
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row) {
      double v = 0;
      for (int k = 0; k < 4; ++k) v += a[size_t(k * 4 + row)] * b[size_t(c * 4 + k)];
      r[size_t(c * 4 + row)] = v;
    }
  return r;
}

double number(const nlohmann::json& j, size_t i, double fallback) {
  return j.is_array() && i < j.size() && j[i].is_number() ? j[i].get<double>() : fallback;
}

// T * R * S (glTF 2.0 §3.5.3), or the node's matrix.
M local(const nlohmann::json& node) {
  if (node.contains("matrix") && node["matrix"].is_array() && node["matrix"].size() == 16) {
    M m;
    for (size_t i = 0; i < 16; ++i) m[i] = number(node["matrix"], i, 0);
    return m;
  }
  const nlohmann::json t = node.value("translation", nlohmann::json::array());
  const nlohmann::json r = node.value("rotation", nlohmann::json::array());
  const nlohmann::json s = node.value("scale", nlohmann::json::array());
  const double x = number(r, 0, 0), y = number(r, 1, 0), z = number(r, 2, 0), w = number(r, 3, 1);
  const double sx = number(s, 0, 1), sy = number(s, 1, 1), sz = number(s, 2, 1);
  M m = identity();
  m[0] = (1 - 2 * (y * y + z * z)) * sx;
  m[1] = (2 * (x * y + z * w)) * sx;
  m[2] = (2 * (x * z - y * w)) * sx;
  m[4] = (2 * (x * y - z * w)) * sy;
  m[5] = (1 - 2 * (x * x + z * z)) * sy;
  m[6] = (2 * (y * z + x * w)) * sy;
  m[8] = (2 * (x * z + y * w)) * sz;
  m[9] = (2 * (y * z - x * w)) * sz;
  m[10] = (1 - 2 * (x * x + y * y)) * sz;
  m[12] = number(t, 0, 0);
  m[13] = number(t, 1, 0);
  m[14] = number(t, 2, 0);
  return m;
}

Result<nlohmann::json> document(const std::string& bytes) {
  std::string text = bytes;
  if (bytes.size() >= 20 && std::memcmp(bytes.data(), "glTF", 4) == 0) {
    // GLB: 12-byte header, then the JSON chunk (length, type "JSON", data).
    uint32_t length = 0, type = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    std::memcpy(&type, bytes.data() + 16, 4);
    if (type != 0x4E4F534Au || size_t{length} > bytes.size() - 20)
      return invalid_argument("settings.probes 'nodes': the GLB has no JSON chunk");
    text = bytes.substr(20, length);
  }
  try {
    return nlohmann::json::parse(text);
  } catch (const std::exception& e) {
    return invalid_argument(std::string("settings.probes 'nodes': the scene is not glTF JSON: ") +
                            e.what());
  }
}

}  // namespace

Result<std::string> probe_nodes_json(const std::string& gltf_or_glb) {
  auto doc = document(gltf_or_glb);
  if (!doc) return doc.status();
  const nlohmann::json& j = doc.value();
  const nlohmann::json nodes = j.value("nodes", nlohmann::json::array());
  const nlohmann::json scenes = j.value("scenes", nlohmann::json::array());
  const size_t scene =
      j.contains("scene") && j["scene"].is_number_unsigned() ? j["scene"].get<size_t>() : 0;
  if (!nodes.is_array() || !scenes.is_array() || scene >= scenes.size())
    return invalid_argument("settings.probes 'nodes': the scene file has no scene");
  nlohmann::json out = nlohmann::json::array();
  // Depth-first down the default scene; a visited set stops malformed cycles.
  std::vector<bool> seen(nodes.size(), false);
  std::vector<std::pair<size_t, M>> stack;
  for (const auto& root : scenes[scene].value("nodes", nlohmann::json::array()))
    if (root.is_number_unsigned() && root.get<size_t>() < nodes.size())
      stack.push_back({root.get<size_t>(), identity()});
  while (!stack.empty()) {
    auto [index, parent] = stack.back();
    stack.pop_back();
    if (seen[index]) continue;
    seen[index] = true;
    const nlohmann::json& node = nodes[index];
    if (!node.is_object()) continue;
    const M world = multiply(parent, local(node));
    const nlohmann::json extras = node.value("extras", nlohmann::json::object());
    if (extras.is_object() && extras.value("luxelProbe", false) == true)
      out.push_back({world[12], world[13], world[14]});
    for (const auto& child : node.value("children", nlohmann::json::array()))
      if (child.is_number_unsigned() && child.get<size_t>() < nodes.size())
        stack.push_back({child.get<size_t>(), world});
  }
  if (out.empty())
    return invalid_argument(
        "settings.probes 'nodes': no node of the scene has extras.luxelProbe = true");
  return out.dump();
}

}  // namespace luxel::probes
