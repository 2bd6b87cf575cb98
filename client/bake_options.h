// The command line of `luxel bake`, shared by the in-process path (--local)
// and the remote path (submit to luxeld): one parser, so both accept the same
// settings options with the same meaning and errors.
#pragma once

#include <string>
#include <vector>

#include "pipeline/bake_settings.h"
#include "remote/connection.h"

namespace luxel::cli {

struct BakeArgs {
  std::string scene;  // a .gltf/.glb file, or (remote) a scene id the daemon stores
  std::string out;    // output folder (required unless --detach)
  bool local = false;
  bool quiet = false;
  pipeline::BakeSettings settings;

  std::string device;  // --local only: OpenCL device
  std::string reference_file;  // --local only: reference lightmap EXR (RGBA)

  // Remote only.
  remote::ConnectionOptions connection;
  std::string name;                // scene display name for the upload
  int priority = 0;                // higher runs first
  double snapshot_interval_s = 0;  // 0: the daemon's default
  std::string snapshot_format;     // "png", "exr", "none"; empty: the daemon's default (png)
  uint32_t snapshot_max_side = 0;  // PNG snapshot longest side; 0: the daemon's default
  std::string snapshots_dir;       // write snapshots while watching
  std::string idempotency_key;
  std::string reference_bake;      // a finished bake on the daemon whose lightmap is the reference
  bool detach = false;             // print the bake id and return after SubmitBake

  // Options given on the command line that only one path understands; the
  // other path refuses them instead of silently ignoring them.
  std::vector<std::string> local_only;
  std::vector<std::string> remote_only;
};

enum class ParseOutcome { kOk, kHelpShown, kUsageError };

// Parses `luxel bake` arguments (errors printed to stderr).
ParseOutcome parse_bake_args(const std::vector<std::string>& args, BakeArgs& out);

// `luxel bake` without --local: upload if needed, submit, watch, download.
int run_bake_remote(BakeArgs& args);

}  // namespace luxel::cli
