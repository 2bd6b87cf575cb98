// The probe files of a bake.
//
// probes.bin (little-endian, version 1), read by client/sdk/luxel_lightmap.h:
//   header, 96 bytes:
//     char  magic[8]       "LUXPROBE"
//     u32   version        1
//     u32   header_bytes   96
//     u32   probe_count
//     u32   sh_count       4 (L1) or 9 (L2)
//     u32   vis_side       LUX_PROBE_VIS_SIDE (visibility bins = side^2)
//     u32   flags          bit 0: a grid layout (grid fields valid)
//     i32   dims[3]        grid cells per axis
//     f32   origin[3]      position of cell (0, 0, 0), world units
//     f32   spacing        grid spacing, world units
//     u32   window         0 none, 1 hanning, 2 lanczos (applied at evaluation)
//     f32   sigma[3]       the window's sigma_0..2
//     u32   mode           0 grid, 1 file, 2 adaptive, 3 nodes (glTF extras)
//     u32   record_bytes   bytes of one probe record
//     u32   reserved[3]    0
//   grid: i32 grid_index[dims0 * dims1 * dims2]   probe of cell i + d0 (j + d1 k), or -1
//   probe records, probe_count of them:
//     f32 position[3]; u32 flags (placement.h ProbeFlag); f32 max_distance;
//     f32 irradiance[3]   scalar irradiance: integral of L over the sphere, W/m^2
//     f32 rel_error       relative standard error of its luminance
//     f32 samples         paths traced from the probe
//     f32 sh[sh_count][3] radiance SH, RGB per coefficient (W/m^2/sr x sr)
//     f32 vis[vis_side^2][2]  per octahedral bin: mean distance, mean squared distance
//
// SH conventions: real, orthonormal over the sphere, world frame, order
// l=0; l=1 (y, z, x); l=2 (xy, yz, 3z^2-1, xz, x^2-y^2) (kernels/shared/bases.h,
// Ramamoorthi & Hanrahan 2001); c_lm = integral of L(w) Y_lm(w) dw, so the
// irradiance about a normal n is E(n) = sum_lm sigma_l A_l c_lm Y_lm(n) with
// A = (pi, 2 pi / 3, pi / 4).
#pragma once

#include <string>

#include "probes/probe_bake.h"

namespace luxel::probes {

inline constexpr uint32_t kProbeFileVersion = 1;
inline constexpr uint32_t kProbeHeaderBytes = 96;

// The bytes of probes.bin.
std::string encode_probe_bin(const ProbeBake& b);
// probes.json: the layout, conventions, units, window, negative-irradiance
// figures and every probe's position, flags, irradiance and coefficients.
std::string encode_probe_json(const ProbeBake& b);
// Writes both files into `dir` (created if needed), and when `dir` holds a lightmap's
// manifest.json, adds a "probes" object to it (layout, files, basis,
// window); INTERNAL naming the file on an I/O error.
Status write_probe_files(const ProbeBake& b, const std::string& dir);

// The manifest's "probes" object (one JSON object).
std::string describe_probes_json(const ProbeBake& b);

}  // namespace luxel::probes
