// The command line of `luxel bake`, shared by the in-process path (--local)
// and the remote path (submit to luxeld): one parser, so both accept the same
// settings options with the same meaning and errors. The settings' options
// and their help come from the settings schema (settings/settings_schema.h).
#pragma once

#include <string>
#include <vector>

#include "remote/connection.h"
#include "settings/bake_settings.h"

namespace luxel::cli {

struct BakeCommand {
  std::string scene;  // a .gltf/.glb file, or (remote) a scene id the daemon stores
  std::string out;    // output folder (required unless --detach)
  bool local = false;
  bool quiet = false;
  // Every schema setting, from the schema's defaults and the options given
  // (settings.reference_name: --reference FILE.exr, loaded by the local path;
  // settings.job: priority, snapshots and reference bake of a remote bake).
  pipeline::BakeSettings settings;

  std::string device;  // --local only: OpenCL device
  // --local only: host bytes the bake may be estimated to need
  // (bake/host_memory.h); -1: half the machine's or cgroup's memory, 0: none.
  double host_memory_budget = -1;

  // Remote only.
  remote::ConnectionOptions connection;
  std::string name;           // scene display name for the upload
  std::string snapshots_dir;  // write snapshots while watching
  std::string idempotency_key;
  bool detach = false;  // print the bake id and return after SubmitBake

  // Options given on the command line that only one path understands; the
  // other path refuses them instead of silently ignoring them.
  std::vector<std::string> local_only;
  std::vector<std::string> remote_only;
};

enum class ParseOutcome { kOk, kHelpShown, kUsageError };

// Parses `luxel bake` arguments (errors printed to stderr).
ParseOutcome parse_bake_args(const std::vector<std::string>& args, BakeCommand& out);

// `--probes file:PATH`: reads PATH into settings.probe_positions, which the
// bake (local or on luxeld) places the probes from; the daemon gets the
// positions, not the path. False (and a message) when it cannot be read.
bool read_probe_positions(BakeCommand& a);

// `luxel bake` without --local: upload if needed, submit, watch, download.
int run_bake_remote(BakeCommand& args);

}  // namespace luxel::cli
