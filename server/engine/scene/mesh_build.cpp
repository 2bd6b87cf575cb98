// See mesh_build.h.
#include "scene/mesh_build.h"

#include <cmath>
#include <limits>

#include "scene/accessor.h"
#include "scene/tangents.h"

namespace luxel::scene::detail {
namespace {

// A triangle whose doubled area |(p1-p0) x (p2-p0)| is below this fraction of
// its longest edge squared is treated as zero-area: its largest angle is
// within ~1e-12 rad of 180 degrees, far below float resolution, so its normal
// is noise and no texel can be sampled on it.
constexpr double kRelativeAreaEpsilon = 1e-12;

const char* mode_name(int mode) {
  switch (mode) {
    case TINYGLTF_MODE_POINTS:
      return "POINTS";
    case TINYGLTF_MODE_LINE:
      return "LINES";
    case TINYGLTF_MODE_LINE_LOOP:
      return "LINE_LOOP";
    case TINYGLTF_MODE_LINE_STRIP:
      return "LINE_STRIP";
    case TINYGLTF_MODE_TRIANGLE_STRIP:
      return "TRIANGLE_STRIP";
    case TINYGLTF_MODE_TRIANGLE_FAN:
      return "TRIANGLE_FAN";
    default:
      return "unknown";
  }
}

struct Attribute {
  const char* semantic;
  int type;
  unsigned normalized;    // FLOAT and the integer types accepted normalized
  unsigned unnormalized;  // integer types accepted as plain values
  std::vector<float>* out;
  bool present = false;
};

// q - p in double (exact for float inputs of similar magnitude).
void diff(const Vec3& q, const Vec3& p, double out[3]) {
  for (int k = 0; k < 3; ++k) out[k] = static_cast<double>(q[k]) - static_cast<double>(p[k]);
}

bool zero_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  double e1[3], e2[3], e3[3];
  diff(b, a, e1);
  diff(c, a, e2);
  diff(c, b, e3);
  const double cx = e1[1] * e2[2] - e1[2] * e2[1];
  const double cy = e1[2] * e2[0] - e1[0] * e2[2];
  const double cz = e1[0] * e2[1] - e1[1] * e2[0];
  const double doubled_area = std::sqrt(cx * cx + cy * cy + cz * cz);
  auto len2 = [](const double* e) { return e[0] * e[0] + e[1] * e[1] + e[2] * e[2]; };
  const double longest2 = std::max({len2(e1), len2(e2), len2(e3)});
  return !(doubled_area > kRelativeAreaEpsilon * longest2);
}

Vec3 vec3_at(const std::vector<float>& v, size_t i) {
  return {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
}

// The capacity `v` grows to (doubling) so that `extra` more elements fit;
// adds the bytes that adds to `bytes`. The capacity freed by the move was
// reserved before, so what stays reserved is the capacity.
template <typename T>
uint64_t grown(const std::vector<T>& v, uint64_t extra, uint64_t* bytes) {
  const uint64_t need = add_sat(v.size(), extra);
  if (need <= v.capacity()) return v.capacity();
  const uint64_t cap = std::max<uint64_t>(need, 2 * uint64_t{v.capacity()});
  *bytes = add_sat(*bytes, mul_sat(cap - v.capacity(), sizeof(T)));
  return cap;
}

// Reserves what a primitive of `vertices` vertices and `list` index-list
// entries (its indices accessor, or the vertices) will allocate, in one
// request before any of it is allocated or read: the mesh arrays it appends
// to (kept for the import) and its working arrays (released with `work`).
Status reserve_primitive(const tinygltf::Primitive& prim, int mode, uint64_t vertices,
                         uint64_t list, const std::string& what, bool file_uv1, bool tangents,
                         ImportBudget* budget, ScopedReservation* work, Mesh* mesh) {
  const uint64_t triangles =
      mode == TINYGLTF_MODE_TRIANGLES ? list / 3 : (list >= 3 ? list - 2 : 0);
  // Generated index list, smooth normals; triangle list copy and kept list,
  // source triangles; tangent generation's positions, UVs and output.
  uint64_t working = mul_sat(vertices, prim.indices >= 0 ? 12 : 16);
  working = add_sat(working, mul_sat(triangles, 3 * 8 + 4));
  if (tangents) working = add_sat(working, mul_sat(vertices, 12 + 8 + 16));
  uint64_t kept = 0;
  const uint64_t positions = grown(mesh->positions, vertices, &kept);
  const uint64_t normals = grown(mesh->normals, vertices, &kept);
  const uint64_t uv0 = grown(mesh->uv0, vertices, &kept);
  const uint64_t uv1 = grown(mesh->uv1, vertices, &kept);
  const uint64_t file_uv1_cap =
      file_uv1 ? grown(mesh->file_uv1, add_sat(mesh->uv1.size() - mesh->file_uv1.size(), vertices),
                       &kept)
               : 0;
  const bool with_tangents = tangents || !mesh->tangents.empty();
  const uint64_t tangents_cap =
      with_tangents
          ? grown(mesh->tangents, add_sat(mesh->positions.size() - mesh->tangents.size(), vertices),
                  &kept)
          : 0;
  const uint64_t indices = grown(mesh->indices, mul_sat(triangles, 3), &kept);
  const uint64_t sources = grown(mesh->source_triangle, triangles, &kept);
  const uint64_t materials = grown(mesh->triangle_material, triangles, &kept);
  LUXEL_RETURN_IF_ERROR(budget->reserve(add_sat(working, kept), what));
  work->adopt(working);
  mesh->positions.reserve(static_cast<size_t>(positions));
  mesh->normals.reserve(static_cast<size_t>(normals));
  mesh->uv0.reserve(static_cast<size_t>(uv0));
  mesh->uv1.reserve(static_cast<size_t>(uv1));
  if (file_uv1) mesh->file_uv1.reserve(static_cast<size_t>(file_uv1_cap));
  if (with_tangents) mesh->tangents.reserve(static_cast<size_t>(tangents_cap));
  mesh->indices.reserve(static_cast<size_t>(indices));
  mesh->source_triangle.reserve(static_cast<size_t>(sources));
  mesh->triangle_material.reserve(static_cast<size_t>(materials));
  return Status::ok();
}

int default_material(const tinygltf::Model& model, Scene* scene) {
  const size_t index = model.materials.size();
  if (scene->materials.size() == index) {
    Material m;  // glTF default: white, metallic 1, roughness 1, opaque
    m.name = "default";
    scene->materials.push_back(m);
  }
  return static_cast<int>(index);
}

// Tangents of one primitive's vertices, appended to mesh->tangents (which
// stays empty while no primitive of the mesh has a normal-mapped material):
// TANGENT when the primitive has it, else generated from the UV set the
// normal texture reads (scene/tangents.h). `kept`: the primitive's triangles.
Status append_tangents(const Material& material, const std::string& ctx,
                       const std::vector<float>* file_tangents, const std::vector<float>& pos,
                       const std::vector<Vec3>& normals, const std::vector<float>* uv0,
                       const std::vector<float>* uv1, const std::vector<uint32_t>& kept,
                       Scene* scene, Mesh* mesh) {
  const size_t base = mesh->positions.size() - normals.size();
  const size_t count = normals.size();
  const TextureRef& map = material.normal_texture;
  if (map.texture < 0) {
    if (!mesh->tangents.empty()) mesh->tangents.resize(base + count, Vec4{0, 0, 0, 1});
    return Status::ok();
  }
  mesh->tangents.resize(base, Vec4{0, 0, 0, 1});
  if (file_tangents) {
    for (size_t i = 0; i < count; ++i) {
      const float* t = &(*file_tangents)[4 * i];
      // glTF 2.0 §3.7.2.1: XYZ unit length, W +1 or -1; normalised here, and
      // a zero or non-finite tangent falls back to one the kernel builds.
      Vec3 xyz = {t[0], t[1], t[2]};
      const float len = length(xyz);
      xyz = len > 0 && std::isfinite(len) ? xyz * (1.0f / len) : Vec3{0, 0, 0};
      mesh->tangents.push_back({xyz.x, xyz.y, xyz.z, t[3] < 0 ? -1.0f : 1.0f});
    }
    return Status::ok();
  }
  const std::vector<float>* uv = map.texcoord == 1 ? uv1 : uv0;
  std::vector<Vec2> uvs(count, Vec2{0, 0});
  if (uv) {
    for (size_t i = 0; i < count; ++i) uvs[i] = {(*uv)[2 * i], (*uv)[2 * i + 1]};
  } else {
    scene->import_stats.warnings.push_back(
        strprintf("%s: material '%s' has a normalTexture on TEXCOORD_%d, which the primitive "
                  "lacks; its tangents are arbitrary",
                  ctx.c_str(), material.name.c_str(), map.texcoord));
  }
  std::vector<Vec3> p(count);
  for (size_t i = 0; i < count; ++i) p[i] = vec3_at(pos, i);
  for (const Vec4& t : generate_tangents(p, normals, uvs, kept)) mesh->tangents.push_back(t);
  return Status::ok();
}

// The TEXCOORD index of the primitive's lightmap UVs: extras.lightmapTexCoord
// when it names a set the primitive has, else 1 (Unity's, Godot's and
// Unreal's default lightmap channel: the second UV set).
int lightmap_texcoord(const tinygltf::Primitive& prim, const std::string& ctx, Scene* scene) {
  if (!prim.extras.IsObject() || !prim.extras.Has("lightmapTexCoord")) return 1;
  const tinygltf::Value& v = prim.extras.Get("lightmapTexCoord");
  const int set = v.IsInt() ? v.GetNumberAsInt() : -1;
  if (set >= 0 && prim.attributes.count("TEXCOORD_" + std::to_string(set))) return set;
  scene->import_stats.warnings.push_back(
      ctx +
      ": extras.lightmapTexCoord names no TEXCOORD set of the primitive; TEXCOORD_1 is "
      "read as its lightmap UVs");
  return 1;
}

Status append_primitive(const tinygltf::Model& model, int mesh_index, int prim_index, int mode,
                        const ImportOptions& options, ImportBudget* budget, Scene* scene,
                        Mesh* mesh) {
  const auto& prim =
      model.meshes[static_cast<size_t>(mesh_index)].primitives[static_cast<size_t>(prim_index)];
  const std::string ctx =
      strprintf("%s primitive %d", mesh_label(model, mesh_index).c_str(), prim_index);

  // The lightmap UVs: the set the primitive's extras.lightmapTexCoord names
  // (Luxel's write-back records it there when TEXCOORD_1 was taken,
  // post/lightmapped_gltf.h), else TEXCOORD_1.
  const int lightmap_set = lightmap_texcoord(prim, ctx, scene);
  const std::string lightmap_name =
      lightmap_set == 1 ? std::string() : "TEXCOORD_" + std::to_string(lightmap_set);
  std::vector<float> pos, nrm, tan, uv0, uv1, lm;
  // Component types of glTF 2.0 §3.7.2.1 widened by KHR_mesh_quantization
  // (its "Extending Mesh Attributes" table).
  constexpr unsigned kInts = kCompI8 | kCompU8 | kCompI16 | kCompU16;
  constexpr unsigned kSigned = kCompF32 | kCompI8 | kCompI16;
  Attribute attrs[] = {
      {"POSITION", TINYGLTF_TYPE_VEC3, kCompF32 | kInts, kInts, &pos},
      {"NORMAL", TINYGLTF_TYPE_VEC3, kSigned, 0, &nrm},
      {"TANGENT", TINYGLTF_TYPE_VEC4, kSigned, 0, &tan},
      {"TEXCOORD_0", TINYGLTF_TYPE_VEC2, kCompF32 | kInts, kInts, &uv0},
      {"TEXCOORD_1", TINYGLTF_TYPE_VEC2, kCompF32 | kInts, kInts, &uv1},
      {lightmap_name.c_str(), TINYGLTF_TYPE_VEC2, kCompF32 | kInts, kInts, &lm},
  };
  // Everything the primitive allocates is reserved from the declared counts
  // before an element is read: a count is only a number in the file.
  ScopedReservation work(budget);
  {
    const auto pos_it = prim.attributes.find("POSITION");
    const int pos_acc = pos_it == prim.attributes.end() ? -1 : pos_it->second;
    const uint64_t vertices = declared_count(model, pos_acc);
    const uint64_t list = prim.indices >= 0 ? declared_count(model, prim.indices) : vertices;
    const bool file_uv1 = lightmap_set != 1 || !mesh->file_uv1.empty();
    const int mat = prim.material;
    const bool tangents = mat >= 0 && static_cast<size_t>(mat) < scene->materials.size() &&
                          scene->materials[static_cast<size_t>(mat)].normal_texture.texture >= 0;
    const std::string what =
        strprintf("%s: accessor %d (POSITION): %llu vertices, %llu %s", ctx.c_str(), pos_acc,
                  static_cast<unsigned long long>(vertices), static_cast<unsigned long long>(list),
                  prim.indices >= 0 ? "indices" : "generated indices");
    LUXEL_RETURN_IF_ERROR(reserve_primitive(prim, mode, vertices, list, what, file_uv1, tangents,
                                            budget, &work, mesh));
  }
  size_t vertex_count = 0;
  for (auto& a : attrs) {
    auto it = prim.attributes.find(a.semantic);
    if (it == prim.attributes.end()) continue;
    LUXEL_RETURN_IF_ERROR(read_floats(model, it->second, a.semantic, a.type, a.normalized,
                                      a.unnormalized, ctx, budget, &work, a.out));
    a.present = true;
    const size_t comps = a.type == TINYGLTF_TYPE_VEC4 ? 4 : a.type == TINYGLTF_TYPE_VEC3 ? 3 : 2;
    const size_t count = a.out->size() / comps;
    if (a.out == &pos) {
      vertex_count = count;
    } else if (count != vertex_count) {
      return invalid_argument(
          strprintf("%s: accessor %d (%s): count %zu differs from the POSITION count %zu",
                    ctx.c_str(), it->second, a.semantic, count, vertex_count));
    }
  }
  if (!attrs[0].present) return invalid_argument(ctx + ": has no POSITION attribute");
  const bool has_lightmap = lightmap_set == 1 ? attrs[4].present : attrs[5].present;
  const std::vector<float>& lightmap_uvs = lightmap_set == 1 ? uv1 : lm;
  if (!has_lightmap && options.require_lightmap_uvs) {
    return invalid_argument(
        ctx +
        ": TEXCOORD_1 (lightmap UVs) is missing; every primitive needs lightmap UVs "
        "(ImportOptions::require_lightmap_uvs)");
  }
  if (!has_lightmap) mesh->has_lightmap_uvs = false;
  const size_t base = mesh->positions.size();
  if (base + vertex_count > std::numeric_limits<uint32_t>::max()) {
    return resource_exhausted(ctx + ": the mesh has more than 2^32 vertices");
  }

  std::vector<uint32_t> indices;
  if (prim.indices >= 0) {
    LUXEL_RETURN_IF_ERROR(read_indices(model, prim.indices, ctx, budget, &work, &indices));
    for (size_t i = 0; i < indices.size(); ++i) {
      if (indices[i] >= vertex_count) {
        return invalid_argument(
            strprintf("%s: accessor %d (indices): index %u at position %zu is out of range "
                      "(POSITION has %zu vertices)",
                      ctx.c_str(), prim.indices, indices[i], i, vertex_count));
      }
    }
  } else {
    indices.resize(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i) indices[i] = static_cast<uint32_t>(i);
  }
  if (mode == TINYGLTF_MODE_TRIANGLES && indices.size() % 3 != 0) {
    return invalid_argument(strprintf("%s: %zu %s is not a multiple of 3 (mode TRIANGLES)",
                                      ctx.c_str(), indices.size(),
                                      prim.indices >= 0 ? "indices" : "vertices"));
  }
  indices = to_triangle_list(mode, indices);

  int material = prim.material;
  if (material < 0) {
    material = default_material(model, scene);
  } else if (static_cast<size_t>(material) >= model.materials.size()) {
    return invalid_argument(strprintf("%s: material %d does not exist (%zu materials)", ctx.c_str(),
                                      material, model.materials.size()));
  }

  // Keep the triangles with three distinct indices and a non-zero area.
  std::vector<uint32_t> kept, kept_source;
  kept.reserve(indices.size());
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    if (t % (3 * kDeadlineStride) == 0) LUXEL_RETURN_IF_ERROR(budget->check_deadline(ctx));
    const uint32_t a = indices[t], b = indices[t + 1], c = indices[t + 2];
    if (a == b || b == c || a == c ||
        zero_area(vec3_at(pos, a), vec3_at(pos, b), vec3_at(pos, c))) {
      ++scene->import_stats.degenerate_triangles_dropped;
      continue;
    }
    kept.insert(kept.end(), {a, b, c});
    kept_source.push_back(static_cast<uint32_t>(t / 3));
  }

  std::vector<Vec3> normals(vertex_count, Vec3{0, 0, 0});
  if (attrs[1].present) {
    for (size_t i = 0; i < vertex_count; ++i) normals[i] = normalize(vec3_at(nrm, i));
  } else {
    // Area-weighted smooth normals over shared vertices (the cross product's
    // length is twice the area). Non-indexed primitives share no vertices, so
    // they get flat normals.
    mesh->generated_normals = true;
    for (size_t t = 0; t < kept.size(); t += 3) {
      if (t % (3 * kDeadlineStride) == 0) LUXEL_RETURN_IF_ERROR(budget->check_deadline(ctx));
      const Vec3 p0 = vec3_at(pos, kept[t]), p1 = vec3_at(pos, kept[t + 1]),
                 p2 = vec3_at(pos, kept[t + 2]);
      const Vec3 n = cross(p1 - p0, p2 - p0);
      for (int k = 0; k < 3; ++k)
        normals[kept[t + static_cast<size_t>(k)]] = normals[kept[t + static_cast<size_t>(k)]] + n;
    }
    for (auto& n : normals) n = normalize(n);
  }

  // Materials keep reading the file's TEXCOORD_1 (Mesh::file_uv1) once a
  // primitive's lightmap set is another one; the primitives before it had
  // their lightmap in TEXCOORD_1, so their copy is uv1 as read.
  const bool keep_file_uv1 = lightmap_set != 1 || !mesh->file_uv1.empty();
  if (keep_file_uv1 && mesh->file_uv1.empty()) mesh->file_uv1 = mesh->uv1;
  for (size_t i = 0; i < vertex_count; ++i) {
    if (i % kDeadlineStride == 0) LUXEL_RETURN_IF_ERROR(budget->check_deadline(ctx));
    mesh->positions.push_back(vec3_at(pos, i));
    mesh->normals.push_back(normals[i]);
    mesh->uv0.push_back(attrs[3].present ? Vec2{uv0[2 * i], uv0[2 * i + 1]} : Vec2{});
    mesh->uv1.push_back(has_lightmap ? Vec2{lightmap_uvs[2 * i], lightmap_uvs[2 * i + 1]} : Vec2{});
    if (keep_file_uv1)
      mesh->file_uv1.push_back(attrs[4].present ? Vec2{uv1[2 * i], uv1[2 * i + 1]} : Vec2{});
  }
  LUXEL_RETURN_IF_ERROR(append_tangents(scene->materials[static_cast<size_t>(material)], ctx,
                                        attrs[2].present ? &tan : nullptr, pos, normals,
                                        attrs[3].present ? &uv0 : nullptr,
                                        attrs[4].present ? &uv1 : nullptr, kept, scene, mesh));
  Mesh::PrimitiveSpan span;
  span.primitive = prim_index;
  span.lightmap_texcoord = lightmap_set;
  span.has_lightmap_uvs = has_lightmap;
  span.first_vertex = static_cast<uint32_t>(base);
  span.vertex_count = static_cast<uint32_t>(vertex_count);
  span.first_triangle = static_cast<uint32_t>(mesh->triangle_count());
  span.triangle_count = static_cast<uint32_t>(kept.size() / 3);
  mesh->primitive_spans.push_back(span);
  mesh->source_triangle.insert(mesh->source_triangle.end(), kept_source.begin(), kept_source.end());
  for (uint32_t i : kept) mesh->indices.push_back(static_cast<uint32_t>(base) + i);
  mesh->triangle_material.insert(mesh->triangle_material.end(), kept.size() / 3, material);
  return Status::ok();
}

}  // namespace

// Strip triangle i is (v_i, v_{i+1+i%2}, v_{i+2-i%2}), which keeps every
// triangle's winding that of the first; fan triangle i is (v_{i+1}, v_{i+2},
// v_0) (glTF 2.0 §3.7.2.1).
std::vector<uint32_t> to_triangle_list(int mode, const std::vector<uint32_t>& v) {
  if (mode == TINYGLTF_MODE_TRIANGLES) return v;
  std::vector<uint32_t> out;
  if (v.size() < 3) return out;
  out.reserve(3 * (v.size() - 2));
  for (size_t i = 0; i + 2 < v.size(); ++i) {
    if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      out.insert(out.end(), {v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]});
    } else {
      out.insert(out.end(), {v[i + 1], v[i + 2], v[0]});
    }
  }
  return out;
}

std::string mesh_label(const tinygltf::Model& model, int mesh_index) {
  const std::string& name = model.meshes[static_cast<size_t>(mesh_index)].name;
  if (name.empty()) return strprintf("mesh[%d]", mesh_index);
  return strprintf("mesh '%s' (mesh[%d])", name.c_str(), mesh_index);
}

Result<Mesh> build_mesh(const tinygltf::Model& model, int mesh_index, const ImportOptions& options,
                        ImportBudget* budget, Scene* scene) {
  const auto& gm = model.meshes[static_cast<size_t>(mesh_index)];
  Mesh mesh;
  mesh.name = gm.name.empty() ? strprintf("mesh[%d]", mesh_index) : gm.name;
  mesh.gltf_index = mesh_index;
  for (size_t p = 0; p < gm.primitives.size(); ++p) {
    int mode = gm.primitives[p].mode;
    if (mode == -1) mode = TINYGLTF_MODE_TRIANGLES;  // the default (glTF 2.0 §5.24)
    if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        mode != TINYGLTF_MODE_TRIANGLE_FAN) {
      // Points and lines have no area to bake; they are left out before any
      // attribute (TEXCOORD_1 included) is required of them.
      ++scene->import_stats.skipped_primitives;
      scene->import_stats.warnings.push_back(
          strprintf("%s primitive %zu: mode %d (%s) has no triangles; skipped",
                    mesh_label(model, mesh_index).c_str(), p, mode, mode_name(mode)));
      continue;
    }
    LUXEL_RETURN_IF_ERROR(append_primitive(model, mesh_index, static_cast<int>(p), mode, options,
                                           budget, scene, &mesh));
  }
  return mesh;
}

}  // namespace luxel::scene::detail
