// Following a bake: the WatchBake server stream drawn as a progress bar (or
// printed as JSON lines), with each snapshot optionally written to a folder.
#pragma once

#include <string>

#include "remote/connection.h"

namespace luxel::cli::remote {

struct WatchOptions {
  std::string snapshots_dir;  // write snapshot_NNNN.png/.exr here; empty = do not
  bool json = false;          // one {"type":"event", ...} line per event
  bool quiet = false;         // no progress bar (human mode)
  int reconnect_s = 60;       // keep retrying this long when the daemon goes away
};

// Follows the bake until its final event and returns the info it carries.
// A stream broken by an unreachable daemon (restart) is re-opened for up to
// `reconnect_s` seconds: the daemon resumes interrupted bakes.
grpc::Status watch_bake(Connection& conn, const std::string& bake_id, const WatchOptions& options,
                        luxel::v1::BakeInfo& final_info);

// kExitOk for SUCCEEDED, kExitBakeFailed otherwise; prints why on stderr.
int bake_outcome(const char* cmd, const luxel::v1::BakeInfo& info);

}  // namespace luxel::cli::remote
