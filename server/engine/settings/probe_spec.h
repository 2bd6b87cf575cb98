// The probe placement setting (settings.probes, `luxel bake --probes`):
// its grammar, parsed once at the edge (validate_settings) and again by the
// placement (probes/placement.h), which documents each mode.
#pragma once

#include <cstddef>
#include <string>

#include "common/choices.h"
#include "common/math.h"
#include "common/status.h"

namespace luxel::probes {

// The modes, named as the spec names them (common/choices.h).
#define LUXEL_PLACEMENT_MODES(X) \
  X(kGrid, "grid") X(kFile, "file") X(kAdaptive, "adaptive") X(kNodes, "nodes")
LUXEL_CHOICE_ENUM(PlacementMode, LUXEL_PLACEMENT_MODES)

struct PlacementSettings {
  PlacementMode mode = PlacementMode::kGrid;
  float spacing = 0.5f;  // grid and adaptive: world units between probes
  bool has_box = false;  // grid and adaptive: over `box` instead of the scene bounds
  Bounds3 box;
  std::string file;  // file mode: the path as given (for the manifest)
  // file mode: the JSON (the CLI reads the file, the service ships it);
  // nodes mode: the same list, of the glTF nodes tagged extras.luxelProbe
  // (probes/gltf_nodes.h, filled by whoever holds the scene file).
  std::string file_contents;
  float keep_distance = 0;  // adaptive: 0 = 1.5 x spacing
  int test_rays = 128;      // classification rays per probe
  float inside_fraction = 0.25f;
  size_t max_probes = size_t{1} << 20;
};

// Parses the `--probes` value (grammar above); file mode leaves
// file_contents empty. INVALID_ARGUMENT names settings.probes.
Result<PlacementSettings> parse_probe_spec(const std::string& spec);
std::string describe_probe_spec(const PlacementSettings& s);  // the inverse of parse

}  // namespace luxel::probes
