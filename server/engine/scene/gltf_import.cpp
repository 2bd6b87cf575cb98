// Entry points of the glTF importer (see gltf_import.h) and the node
// hierarchy: scene selection, transforms, instancing, cycle checks.
#include "scene/gltf_import.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>

#include "scene/accessor.h"
#include "scene/gltf_decompress.h"
#include "scene/gltf_load.h"
#include "scene/lights.h"
#include "scene/materials.h"
#include "scene/mesh_build.h"
#include "scene/scene_stats.h"

namespace luxel::scene {
namespace {

using detail::build_mesh;
using detail::ImportBudget;
using detail::kDeadlineStride;
using detail::ScopedReservation;

// Material-level extensions are listed in materials.cpp; these are read by
// mesh_build.cpp and instantiate() below.
bool supported_extension(const std::string& name) {
  // The compressed-geometry extensions are decoded before tinygltf parses
  // the file (scene/gltf_decompress.h), so a model never lists them; they
  // are named here for what the file says.
  return detail::is_supported_extension(name) || name == "KHR_mesh_quantization" ||
         name == "EXT_mesh_gpu_instancing" || name == kDracoExtension || name == kMeshoptExtension;
}

std::string node_label(const tinygltf::Model& model, int i) {
  const std::string& name = model.nodes[static_cast<size_t>(i)].name;
  return name.empty() ? strprintf("node[%d]", i)
                      : strprintf("node '%s' (node[%d])", name.c_str(), i);
}

bool all_finite(const std::vector<double>& v) {
  for (double x : v) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

// The node's local transform: `matrix` when given, else T * R * S.
Result<Mat4> local_transform(const tinygltf::Model& model, int i) {
  const auto& n = model.nodes[static_cast<size_t>(i)];
  auto bad = [&](const char* what) {
    return invalid_argument(strprintf("%s: %s", node_label(model, i).c_str(), what));
  };
  if (!all_finite(n.matrix) || !all_finite(n.translation) || !all_finite(n.rotation) ||
      !all_finite(n.scale)) {
    return bad("transform has a NaN or infinite value");
  }
  if (n.matrix.size() == 16) {
    Mat4 m;
    for (size_t k = 0; k < 16; ++k) m.m[k] = n.matrix[k];  // both column-major
    return m;
  }
  if (!n.matrix.empty()) return bad("matrix must have 16 numbers");
  if (!(n.translation.empty() || n.translation.size() == 3))
    return bad("translation must have 3 numbers");
  if (!(n.rotation.empty() || n.rotation.size() == 4)) return bad("rotation must have 4 numbers");
  if (!(n.scale.empty() || n.scale.size() == 3)) return bad("scale must have 3 numbers");
  double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
  for (size_t k = 0; k < n.translation.size(); ++k) t[k] = n.translation[k];
  for (size_t k = 0; k < n.scale.size(); ++k) s[k] = n.scale[k];
  if (!n.rotation.empty()) {
    const double len = std::sqrt(n.rotation[0] * n.rotation[0] + n.rotation[1] * n.rotation[1] +
                                 n.rotation[2] * n.rotation[2] + n.rotation[3] * n.rotation[3]);
    if (!(len > 0) || !std::isfinite(len)) return bad("rotation quaternion has zero length");
    // Exporters write quaternions rounded to a few digits; renormalize.
    for (size_t k = 0; k < 4; ++k) q[k] = n.rotation[k] / len;
  }
  return mat4_from_trs(t, q, s);
}

// EXT_mesh_gpu_instancing: the per-instance transforms of a node, T * R * S
// from its TRANSLATION / ROTATION / SCALE accessors (each optional, all of
// one count), to be applied before the node's own world transform. Empty
// when the node does not use the extension.
// An attribute's accessor index: a JSON integer. tinygltf keeps an integer
// that does not fit an int as a double, and converting that to int is
// undefined (the import fuzzer found ROTATION: 1.1e50), so a number that is
// not an integer in [0, INT_MAX] is refused by name before any conversion.
Result<int> accessor_index(const tinygltf::Value& v, const std::string& what) {
  if (v.IsInt()) return v.Get<int>();
  const double d = v.GetNumberAsDouble();
  if (d >= 0 && d <= double(std::numeric_limits<int>::max()) && d == std::floor(d))
    return static_cast<int>(d);
  return invalid_argument(strprintf("%s: accessor index %g is not an integer in [0, %d]",
                                    what.c_str(), d, std::numeric_limits<int>::max()));
}

Status instance_transforms(const tinygltf::Model& model, int node_index, ImportBudget* budget,
                           std::vector<Mat4>* out) {
  out->clear();
  const auto& node = model.nodes[static_cast<size_t>(node_index)];
  auto ext = node.extensions.find("EXT_mesh_gpu_instancing");
  if (ext == node.extensions.end()) return Status::ok();
  const std::string ctx = node_label(model, node_index) + " EXT_mesh_gpu_instancing";
  const tinygltf::Value& attributes = ext->second.Get("attributes");
  if (!attributes.IsObject())
    return invalid_argument(ctx + ": attributes is missing or not an object");
  // Component types of the extension's attribute table (with
  // KHR_mesh_quantization's integer forms for TRANSLATION and SCALE).
  using namespace detail;
  constexpr unsigned kInts = kCompI8 | kCompU8 | kCompI16 | kCompU16;
  struct Attr {
    const char* name;
    int type;
    unsigned normalized, unnormalized;
    std::vector<float> values;
    bool present = false;
  } attrs[] = {{"TRANSLATION", TINYGLTF_TYPE_VEC3, kCompF32 | kInts, kInts, {}},
               {"ROTATION", TINYGLTF_TYPE_VEC4, kCompF32 | kCompI8 | kCompI16, 0, {}},
               {"SCALE", TINYGLTF_TYPE_VEC3, kCompF32 | kInts, kInts, {}}};
  size_t count = 0;
  bool any = false;
  // The instances themselves (records, names, transforms) are reserved from
  // the declared count before their attributes are read: a million
  // instances are 8 KB of JSON.
  for (auto& a : attrs) {
    const tinygltf::Value& v = attributes.Get(a.name);
    if (!v.IsNumber() && !v.IsInt()) continue;
    auto index = accessor_index(v, ctx + " " + a.name);
    if (!index) return index.status();
    const int acc = index.value();
    if (acc < 0 || static_cast<size_t>(acc) >= model.accessors.size()) continue;  // read_floats
    const uint64_t declared = declared_count(model, acc);
    LUXEL_RETURN_IF_ERROR(
        budget->reserve(mul_sat(declared, bytes_per_instance()),
                        strprintf("%s: accessor %d (%s): %llu instances", ctx.c_str(), acc, a.name,
                                  static_cast<unsigned long long>(declared))));
    break;
  }
  ScopedReservation values(budget);
  for (auto& a : attrs) {
    const tinygltf::Value& v = attributes.Get(a.name);
    if (!v.IsNumber() && !v.IsInt()) continue;
    auto index = accessor_index(v, ctx + " " + a.name);
    if (!index) return index.status();
    LUXEL_RETURN_IF_ERROR(read_floats(model, index.value(), a.name, a.type, a.normalized,
                                      a.unnormalized, ctx, budget, &values, &a.values));
    const size_t n = a.values.size() / (a.type == TINYGLTF_TYPE_VEC4 ? 4 : 3);
    if (any && n != count) {
      return invalid_argument(strprintf("%s: %s has %zu elements, the other attributes %zu",
                                        ctx.c_str(), a.name, n, count));
    }
    count = n;
    any = a.present = true;
  }
  if (!any) return invalid_argument(ctx + ": none of TRANSLATION, ROTATION, SCALE is given");
  out->reserve(count);
  for (size_t i = 0; i < count; ++i) {
    if (i % kDeadlineStride == 0) LUXEL_RETURN_IF_ERROR(budget->check_deadline(ctx));
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, sc[3] = {1, 1, 1};
    for (size_t k = 0; k < 3; ++k) {
      if (attrs[0].present) t[k] = attrs[0].values[3 * i + k];
      if (attrs[2].present) sc[k] = attrs[2].values[3 * i + k];
    }
    if (attrs[1].present) {
      double len = 0;
      for (size_t k = 0; k < 4; ++k) {
        q[k] = attrs[1].values[4 * i + k];
        len += q[k] * q[k];
      }
      len = std::sqrt(len);
      if (!(len > 0)) {
        return invalid_argument(
            strprintf("%s: ROTATION of instance %zu has zero length", ctx.c_str(), i));
      }
      for (double& c : q) c /= len;  // quantized rotations are only nearly unit
    }
    out->push_back(mat4_from_trs(t, q, sc));
  }
  return Status::ok();
}

// Builds parent links and rejects nodes with several parents and cycles
// (glTF requires the nodes to form disjoint trees).
Status check_hierarchy(const tinygltf::Model& model, std::vector<int>* parent) {
  const size_t n = model.nodes.size();
  parent->assign(n, -1);
  for (size_t p = 0; p < n; ++p) {
    for (int c : model.nodes[p].children) {
      if (c < 0 || static_cast<size_t>(c) >= n) {
        return invalid_argument(strprintf("%s: child %d does not exist (%zu nodes)",
                                          node_label(model, static_cast<int>(p)).c_str(), c, n));
      }
      int& slot = (*parent)[static_cast<size_t>(c)];
      if (slot >= 0) {
        return invalid_argument(
            strprintf("%s has several parents (node[%d] and node[%zu]); a node may have only "
                      "one parent",
                      node_label(model, c).c_str(), slot, p));
      }
      slot = static_cast<int>(p);
    }
  }
  // Walk up from every node; each node is settled once, so this is O(n)
  // and needs no recursion however deep the hierarchy is.
  std::vector<uint8_t> state(n, 0);  // 0 new, 1 on the current path, 2 settled
  std::vector<int> path;
  for (size_t start = 0; start < n; ++start) {
    path.clear();
    int i = static_cast<int>(start);
    while (i >= 0 && state[static_cast<size_t>(i)] == 0) {
      state[static_cast<size_t>(i)] = 1;
      path.push_back(i);
      i = (*parent)[static_cast<size_t>(i)];
    }
    if (i >= 0 && state[static_cast<size_t>(i)] == 1) {
      return invalid_argument(
          strprintf("%s is part of a cycle in the node hierarchy", node_label(model, i).c_str()));
    }
    for (int k : path) state[static_cast<size_t>(k)] = 2;
  }
  return Status::ok();
}

Result<std::vector<int>> scene_roots(const tinygltf::Model& model, const std::vector<int>& parent) {
  std::vector<int> roots;
  if (model.scenes.empty()) {
    for (size_t i = 0; i < model.nodes.size(); ++i) {
      if (parent[i] < 0) roots.push_back(static_cast<int>(i));
    }
    return roots;
  }
  int s = model.defaultScene;
  if (s >= 0 && static_cast<size_t>(s) >= model.scenes.size()) {
    return invalid_argument(strprintf("scene %d (the default scene) does not exist (%zu scenes)", s,
                                      model.scenes.size()));
  }
  if (s < 0) s = 0;
  std::vector<uint8_t> seen(model.nodes.size(), 0);
  for (int r : model.scenes[static_cast<size_t>(s)].nodes) {
    if (r < 0 || static_cast<size_t>(r) >= model.nodes.size()) {
      return invalid_argument(
          strprintf("scene %d: node %d does not exist (%zu nodes)", s, r, model.nodes.size()));
    }
    if (parent[static_cast<size_t>(r)] >= 0) {
      return invalid_argument(
          strprintf("scene %d: %s is listed as a root but is a child of node[%d]", s,
                    node_label(model, r).c_str(), parent[static_cast<size_t>(r)]));
    }
    if (seen[static_cast<size_t>(r)]++) {
      return invalid_argument(
          strprintf("scene %d: %s is listed twice", s, node_label(model, r).c_str()));
    }
    roots.push_back(r);
  }
  return roots;
}

// extras.lightmapScaleOffset (and lightmapIndex, the page) of a node, or
// entry `element` of lightmapScaleOffsets (lightmapIndices) for the
// instances of an EXT_mesh_gpu_instancing node: absent, or four finite
// numbers with non-zero scales and a page in [0, 1024); anything else is
// INVALID_ARGUMENT naming the node.
Status read_lightmap_scale_offset(const tinygltf::Model& model, int node_index, int element,
                                  Instance* inst) {
  const tinygltf::Value& extras = model.nodes[static_cast<size_t>(node_index)].extras;
  const char* key = element < 0 ? "lightmapScaleOffset" : "lightmapScaleOffsets";
  const char* page_key = element < 0 ? "lightmapIndex" : "lightmapIndices";
  if (!extras.IsObject() || !extras.Has(key)) return Status::ok();
  std::string where = node_label(model, node_index) + ": extras." + key;
  const tinygltf::Value* v = &extras.Get(key);
  if (element >= 0) {
    if (!v->IsArray() || element >= static_cast<int>(v->ArrayLen()))
      return invalid_argument(strprintf("%s has no entry for instance %d", where.c_str(), element));
    v = &v->Get(element);
    where += strprintf("[%d]", element);
  }
  if (!v->IsArray() || v->ArrayLen() != 4)
    return invalid_argument(where + " must be an array of 4 numbers [sx, sy, ox, oy]");
  for (int k = 0; k < 4; ++k) {
    const tinygltf::Value& e = v->Get(k);
    if (!e.IsNumber())
      return invalid_argument(strprintf("%s[%d] is not a number", where.c_str(), k));
    const double d = e.GetNumberAsDouble();
    if (!std::isfinite(d) || (k < 2 && d == 0) || std::fabs(d) > 1e6)
      return invalid_argument(
          strprintf("%s[%d] is %g; scales must be non-zero and every entry "
                    "finite and at most 1e6 in magnitude",
                    where.c_str(), k, d));
    inst->lightmap_scale_offset[k] = static_cast<float>(d);
  }
  inst->has_lightmap_scale_offset = true;
  inst->lightmap_page = 0;
  if (extras.Has(page_key)) {
    const tinygltf::Value* p = &extras.Get(page_key);
    if (element >= 0)
      p = p->IsArray() && element < static_cast<int>(p->ArrayLen()) ? &p->Get(element) : nullptr;
    const double d = p && p->IsNumber() ? p->GetNumberAsDouble() : -1;
    if (!(d >= 0 && d < 1024 && d == std::floor(d)))
      return invalid_argument(node_label(model, node_index) + ": extras." + page_key +
                              " must be a whole number in [0, 1024) (the lightmap page)");
    inst->lightmap_page = static_cast<int>(d);
  }
  return Status::ok();
}

Status instantiate(const tinygltf::Model& model, const ImportOptions& options, ImportBudget* budget,
                   Scene* scene) {
  std::vector<int> parent;
  LUXEL_RETURN_IF_ERROR(check_hierarchy(model, &parent));
  auto roots = scene_roots(model, parent);
  if (!roots) return roots.status();

  std::vector<int> mesh_slot(model.meshes.size(), -1);
  struct Item {
    int node;
    Mat4 parent_world;
  };
  std::vector<Item> stack;
  std::vector<Mat4> per_instance;
  for (auto it = roots->rbegin(); it != roots->rend(); ++it) stack.push_back({*it, Mat4{}});
  while (!stack.empty()) {
    const Item item = stack.back();
    stack.pop_back();
    LUXEL_RETURN_IF_ERROR(budget->check_deadline(node_label(model, item.node)));
    const auto& node = model.nodes[static_cast<size_t>(item.node)];
    auto local = local_transform(model, item.node);
    if (!local) return local.status();
    const Mat4 world = item.parent_world * *local;
    for (double v : world.m) {
      if (!std::isfinite(v)) {
        return invalid_argument(node_label(model, item.node) + ": the world transform overflows");
      }
    }
    if (node.mesh >= 0 || node.mesh < -1) {
      if (static_cast<size_t>(node.mesh) >= model.meshes.size()) {
        return invalid_argument(strprintf("%s: mesh %d does not exist (%zu meshes)",
                                          node_label(model, item.node).c_str(), node.mesh,
                                          model.meshes.size()));
      }
      int& slot = mesh_slot[static_cast<size_t>(node.mesh)];
      if (slot < 0) {
        auto mesh = build_mesh(model, node.mesh, options, budget, scene);
        if (!mesh) return mesh.status();
        scene->meshes.push_back(std::move(*mesh));
        slot = static_cast<int>(scene->meshes.size() - 1);
      }
      // A mesh of points and lines only (its primitives were skipped) has
      // nothing to bake, occlude or lay out: no instance, so neither the
      // atlas nor the write-back gives it a place.
      const bool has_triangle_primitive =
          !scene->meshes[static_cast<size_t>(slot)].primitive_spans.empty();
      Instance inst;
      inst.name = node.name.empty() ? strprintf("node[%d]", item.node) : node.name;
      inst.node_index = item.node;
      inst.mesh = slot;
      inst.object_to_world = world;
      LUXEL_RETURN_IF_ERROR(read_lightmap_scale_offset(model, item.node, -1, &inst));
      LUXEL_RETURN_IF_ERROR(instance_transforms(model, item.node, budget, &per_instance));
      if (!has_triangle_primitive) {
        // (skipped; see above)
      } else if (per_instance.empty()) {
        scene->instances.push_back(std::move(inst));
      } else {
        // EXT_mesh_gpu_instancing: each instance's TRS is expressed in the
        // node's space, so the node's world transform applies after it.
        for (size_t k = 0; k < per_instance.size(); ++k) {
          if (k % kDeadlineStride == 0)
            LUXEL_RETURN_IF_ERROR(budget->check_deadline(node_label(model, item.node)));
          Instance copy = inst;
          copy.name = strprintf("node '%s' instance %zu", inst.name.c_str(), k);
          copy.instance_element = static_cast<int>(k);
          LUXEL_RETURN_IF_ERROR(
              read_lightmap_scale_offset(model, item.node, static_cast<int>(k), &copy));
          copy.object_to_world = world * per_instance[k];
          for (double v : copy.object_to_world.m) {
            if (!std::isfinite(v)) {
              return invalid_argument(strprintf("%s: the world transform of instance %zu overflows",
                                                node_label(model, item.node).c_str(), k));
            }
          }
          scene->instances.push_back(std::move(copy));
        }
      }
    }
    LUXEL_RETURN_IF_ERROR(
        detail::convert_node_light(model, item.node, node_label(model, item.node), world, scene));
    for (auto c = node.children.rbegin(); c != node.children.rend(); ++c)
      stack.push_back({*c, world});
  }
  return Status::ok();
}

Result<Scene> import_model(std::string_view bytes, const std::string& base_dir,
                           const std::string& name, const ImportOptions& options) {
  ImportBudget budget(options.memory_pool, options.max_import_bytes, options.max_accessor_elements,
                      options.timeout_seconds);
  // The file's bytes and tinygltf's copy of its buffers.
  LUXEL_RETURN_IF_ERROR(
      budget.reserve(detail::mul_sat(bytes.size(), 2),
                     strprintf("'%s': %zu bytes of glTF", name.c_str(), bytes.size())));
  tinygltf::Model model;
  LUXEL_RETURN_IF_ERROR(detail::load_model(bytes, base_dir, name, &budget, &model));
  LUXEL_RETURN_IF_ERROR(budget.check_deadline("'" + name + "'"));
  Scene scene;
  scene.source_name = name;
  // glTF 2.0 §3.12: a file that requires an extension the loader does not
  // implement must not be loaded.
  for (const std::string& ext : model.extensionsRequired) {
    // KHR_texture_basisu is read only for its fallback: a texture's core
    // source, which a file that requires the extension does not have to
    // carry (the extension's "Using Without a Fallback").
    if (ext == "KHR_texture_basisu")
      return invalid_argument(
          "extension KHR_texture_basisu is required by the file (extensionsRequired): its "
          "KTX2 / Basis Universal images are not decoded, and a file that requires the "
          "extension need not carry PNG/JPEG fallback sources; export the textures as PNG or "
          "JPEG, or list the extension in extensionsUsed only, with fallback sources");
    if (!supported_extension(ext))
      return invalid_argument("extension " + ext +
                              " is required by the file (extensionsRequired) and not supported");
  }
  // Extensions the file uses that the importer does not read, by name
  // (materials and textures name where each one appears).
  for (const std::string& ext : model.extensionsUsed)
    if (!supported_extension(ext))
      scene.import_stats.warnings.push_back("extension " + ext +
                                            " is used by the file and not supported (ignored)");
  LUXEL_RETURN_IF_ERROR(detail::convert_materials(model, options, &budget, &scene));
  LUXEL_RETURN_IF_ERROR(instantiate(model, options, &budget, &scene));
  LUXEL_RETURN_IF_ERROR(budget.check_deadline("'" + name + "'"));
  // Overlapping lightmap UVs make two surfaces share texels; named here so
  // that a caller can regenerate the UVs of those meshes (find_uv_overlaps).
  constexpr int kOverlapResolution = 512;
  for (const UvOverlap& o : find_uv_overlaps(scene, kOverlapResolution)) {
    Mesh& m = scene.meshes[static_cast<size_t>(o.mesh)];
    m.lightmap_uv_overlap_texels = o.texels;
    scene.import_stats.warnings.push_back(
        strprintf("%s: TEXCOORD_1 (lightmap UVs) overlaps itself at %zu of %d^2 texel centres; two "
                  "surfaces would share lightmap texels",
                  detail::mesh_label(model, m.gltf_index).c_str(), o.texels, kOverlapResolution));
  }
  if (scene.materials.empty()) {
    Material m;
    m.name = "default";
    scene.materials.push_back(m);
  }
  scene.import_stats.peak_reserved_bytes = budget.peak();
  return scene;
}

}  // namespace

Result<Scene> import_gltf_memory(std::string_view bytes, const std::string& base_dir,
                                 const std::string& name, const ImportOptions& options) {
  // Library code below may still throw on hostile input (allocation failure,
  // container limits); a bad upload must become an error, not a crash.
  try {
    auto scene = import_model(bytes, base_dir, name, options);
    if (!scene) {
      const Status& st = scene.status();
      // Prefix the file name unless the message already starts with it.
      const std::string prefix = "'" + name + "'";
      if (st.message().rfind(prefix, 0) == 0) return st;
      return Status(st.code(), prefix + ": " + st.message());
    }
    return scene;
  } catch (const std::bad_alloc&) {
    return resource_exhausted(strprintf("'%s': out of memory while importing", name.c_str()));
  } catch (const std::exception& e) {
    return invalid_argument(strprintf("'%s': malformed glTF: %s", name.c_str(), e.what()));
  }
}

Result<Scene> import_gltf_file(const std::string& path, const ImportOptions& options) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return not_found(strprintf("'%s': cannot open the file", path.c_str()));
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) return data_loss(strprintf("'%s': read error", path.c_str()));
  const std::string bytes = ss.str();
  std::string base = std::filesystem::path(path).parent_path().string();
  if (base.empty()) base = ".";
  return import_gltf_memory(bytes, base, path, options);
}

}  // namespace luxel::scene
