// Light-probe placement (support document 000, the DDGI article: a probe
// grid, probe classification and relocation).
//
//   grid:S            a regular grid of spacing S over the scene bounds;
//   grid:S:box=x0,y0,z0,x1,y1,z1   the same over a given box;
//   file:P.json       user positions: [[x,y,z], ...], or {"probes": [...]}
//                     whose entries are [x,y,z] or {"position": [x,y,z]};
//   nodes             the glTF nodes tagged extras.luxelProbe = true
//                     (gltf_nodes.h; the caller fills file_contents);
//   adaptive:S        the grid of spacing S, keeping only probes within
//                     keep_distance (default 1.5 S) of geometry, and moving
//                     probes that sit inside closed geometry out of it.
//
// Every mode tests each probe with `test_rays` rays (a spherical Fibonacci
// set): a probe that sees back faces in more than `inside_fraction` of its
// directions is inside closed geometry (DDGI's classification uses 25 %).
// Adaptive mode moves it through the nearest back face it sees, just past
// that face (DDGI probe relocation), and tests again; a probe that is still
// inside, or any inside probe of the grid and file modes, is kept and
// FLAGGED (kProbeInside), never silently black. Deterministic: no random
// numbers, Embree's robust traversal on the host.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/cancel.h"
#include "common/math.h"
#include "common/status.h"
#include "scene/scene.h"
#include "settings/probe_spec.h"

namespace luxel::probes {

// Per-probe flags (probes.bin, probes.json).
enum ProbeFlag : uint32_t {
  kProbeMoved = 1u,   // moved out of closed geometry (adaptive)
  kProbeInside = 2u,  // inside closed geometry and left there: its light is not the room's
  kProbeUser = 4u,    // a user position (file mode)
};

struct ProbeLayout {
  PlacementMode mode = PlacementMode::kGrid;
  std::vector<Vec3> positions;
  std::vector<uint32_t> flags;
  std::vector<float> max_distance;  // visibility cap per probe (a miss counts as it)
  // Grid and adaptive modes: the lattice. Probe of cell (i, j, k) sits at
  // origin + spacing * (i, j, k) (before relocation); grid_index[i + dims[0]
  // * (j + dims[1] * k)] is its probe index, or -1 where adaptive dropped it.
  bool grid = false;
  int dims[3] = {0, 0, 0};
  Vec3 origin{0, 0, 0};
  float spacing = 0;
  std::vector<int32_t> grid_index;
  // Classification counts.
  size_t inside_detected = 0;  // probes found inside before any move
  size_t moved = 0;            // of those, moved out (adaptive)
  size_t flagged_inside = 0;   // left inside (flag kProbeInside)
  size_t dropped_far = 0;      // adaptive: grid probes with no geometry within keep_distance
  double seconds = 0;
  std::string describe_json() const;  // the manifest's "probes.layout" object
};

// What placement knows before a ray is traced: the positions of the file
// and nodes modes, read and checked, and the grid's lattice over the box or
// the scene's triangles, its size counted in doubles (a spacing of 1e-9, or
// a box of +-1e30, overflows an int). place_probes starts from it, and the
// daemon (SubmitBake) and the CLI call it before queueing, so a placement
// that cannot be baked is refused at submit with the same message.
struct PlacementPlan {
  std::vector<Vec3> positions;  // file and nodes modes
  bool grid = false;            // grid and adaptive modes
  int dims[3] = {0, 0, 0};
  Bounds3 box;
  size_t count = 0;  // probes before adaptive drops any
};
Result<PlacementPlan> plan_placement(const scene::Scene& scene, const PlacementSettings& settings);

// Places the probes of `settings` in the scene. INVALID_ARGUMENT for a
// malformed file, an empty box or scene; RESOURCE_EXHAUSTED past
// settings.max_probes.
// cancel: polled between blocks of probes while they are classified (a
// million probes are 128 million test rays); a request ends it with
// cancelled_error (common/cancel.h).
Result<ProbeLayout> place_probes(const scene::Scene& scene, const PlacementSettings& settings,
                                 CancelToken cancel = {});

}  // namespace luxel::probes
