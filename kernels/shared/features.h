/* The kernel features, declared once for host and device.
 *
 * A feature is a build option -DLUX_<NAME>=<value> that the host passes when
 * it compiles a program (server/engine/device/feature_set.h), so a compiled
 * program holds only the code paths its scene and settings need (DESIGN.md:
 * "leave out what a scene does not need"). A feature that is off is not
 * defined at all: kernels test it with `#if LUX_<NAME>`. The options are
 * part of the program cache key (device/program_cache.h).
 *
 * LUX_FEATURES(X) lists them as X(NAME, kind, what):
 *   NAME  the macro without LUX_; the host's device::Feature::NAME
 *   kind  flag   defined as 1 when on
 *         value  an integer the kernels read (absent: the kernel's default,
 *                or an #error where there is none)
 *   what  what it compiles in, and where (host: read by no kernel).
 * The host's enum comes from this list, so a misspelt feature is a compile
 * error there; device_test checks that every LUX_ name a kernel tests in a
 * preprocessor condition is a feature here or a macro the kernels define,
 * so a misspelt `#if LUX_...` fails too. */
#ifndef LUXEL_SHARED_FEATURES_H
#define LUXEL_SHARED_FEATURES_H

#include "shared/compat.h"

#define LUX_FEATURES(X)                                                                        \
  /* Lights present (bake.cl; kernels/shared/light.h, kernels/shading/lights.h). */            \
  X(LIGHT_POINT, flag, "point lights")                                                         \
  X(LIGHT_SPOT, flag, "spot lights")                                                           \
  X(LIGHT_DIRECTIONAL, flag, "directional lights and the settings' sun")                       \
  X(LIGHT_EMISSIVE, flag, "emissive triangles")                                                \
  X(SKY, flag, "a constant-colour sky")                                                        \
  X(SKY_IMAGE, flag, "an equirectangular sky image, importance sampled")                       \
  X(NEE, flag, "any light at all: next-event estimation")                                      \
  /* Materials (bake.cl). */                                                                   \
  X(TEXTURES, flag, "material textures (base colour, metallic-roughness)")                     \
  X(EMISSIVE_TEXTURE, flag, "an emissive material that is a light has a texture")              \
  X(NORMAL_MAP, flag, "a material has a normal map: per-triangle tangents are bound")          \
  X(TEXCOORD1, flag, "a texture reads TEXCOORD_1: the material uv1 buffer is bound")           \
  X(SPECULAR, flag, "some material needs the GGX layer")                                       \
  /* The bake (bake.cl, kernels/bake/). */                                                     \
  X(SORT_DIRECTIONS, flag, "extension rays are tagged with their octant (thesis 5.4)")         \
  X(COMPACTION, flag, "host: live paths compacted between bounces (thesis 5.1), else all run") \
  X(FILTER_GAUSSIAN, flag, "1.5-texel Gaussian accumulation filter (thesis 3.2.2)")            \
  X(SEQUENCE_RANDOM, flag, "independent random numbers instead of Sobol (ablation)")           \
  X(ADAPTIVE, flag, "paths go by per-texel error after a warm-up, else alloc_* are empty")     \
  X(DIRECT_ANALYTIC, flag, "irradiance: closed-form direct light, sampled shadows (raygen.h)") \
  X(BASIS, flag, "directional encodings: each path leaves a LuxBasisSample (bake/basis.h)")    \
  X(PROBES, flag, "the bake's texels are light probes (server/engine/probes/)")                \
  X(RADIANCE_CACHE, flag, "first hits read their texel's cache (bake/radiance_cache.h)")       \
  X(GUIDING, flag, "first directions from a learned texel histogram (bake/guiding.h)")         \
  /* Ray queries (intersect.cl). */                                                            \
  X(BVH4, flag, "four-wide BVH nodes (intersect/trace_bvh4.h), else the fat BVH2")             \
  X(ALPHA_MASK, flag, "alphaMode MASK triangles run the alpha test")                           \
  X(STACK_SIZE, value, "traversal stack entries (intersect/traverse.h; default 64)")           \
  X(INTERSECTOR_EMBREE, flag, "host: ray queries run in Embree (reported, not compiled)")      \
  /* Data-parallel primitives (primitives/tile.h, radix_sort.cl, compact.cl). */               \
  X(PRIM_WG, value, "work-group size, a power of two")                                         \
  X(PRIM_ITEMS, value, "elements per work-item in one tile")                                   \
  X(PRIM_LOCAL_REORDER, flag, "the radix scatter reorders each tile in local memory (GPUs)")

#ifndef LUX_DEVICE
namespace luxel::device {

/* One enumerator per feature, named as its macro (Feature::NEE is LUX_NEE). */
enum class Feature {
#define LUX_FEATURE_ENUMERATOR(name, kind, what) name,
  LUX_FEATURES(LUX_FEATURE_ENUMERATOR)
#undef LUX_FEATURE_ENUMERATOR
};

#define LUX_FEATURE_ONE(name, kind, what) +1
inline constexpr int kFeatureCount = 0 LUX_FEATURES(LUX_FEATURE_ONE);
#undef LUX_FEATURE_ONE

}  // namespace luxel::device
#endif /* LUX_DEVICE */

#endif /* LUXEL_SHARED_FEATURES_H */
