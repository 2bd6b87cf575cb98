// `luxel status BAKE`, `luxel list [--state S]... | --scenes`, `luxel cancel BAKE`:
// the unary queries, each under the --timeout deadline.
#include <cstdio>
#include <sstream>

#include "commands.h"
#include "remote/connection.h"
#include "remote/output.h"

namespace luxel::cli {
namespace {

using namespace remote;

// Parses the shared options plus positionals; `extra` handles command flags
// (returns false for an unknown one). Returns -1 to go on, else an exit code.
template <typename Extra>
int parse_common(const char* cmd, const char* usage, const std::vector<std::string>& args,
                 ConnectionOptions& copt, std::vector<std::string>& positional, Extra extra) {
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& k = args[i];
    const OptionMatch m = take_connection_option(cmd, args, i, copt);
    if (m == OptionMatch::kError) return kExitUsage;
    if (m == OptionMatch::kTaken) continue;
    if (k == "--help" || k == "-h") {
      std::printf("%s%s", usage, kConnectionUsage);
      return kExitOk;
    }
    if (!k.empty() && k[0] == '-') {
      if (extra(args, i)) continue;
      std::fprintf(stderr, "luxel %s: unknown option or missing value '%s'\n%s", cmd, k.c_str(),
                   usage);
      return kExitUsage;
    }
    positional.push_back(k);
  }
  return -1;
}

auto no_extra = [](const std::vector<std::string>&, size_t&) { return false; };

// Status and cancel: one BAKE id, one unary call returning BakeInfo.
template <typename Call, typename Extra = decltype(no_extra)>
int bake_call(const char* cmd, const char* usage, const std::vector<std::string>& args, Call call,
              Extra extra = no_extra) {
  ConnectionOptions copt = default_connection_options();
  std::vector<std::string> pos;
  if (int rc = parse_common(cmd, usage, args, copt, pos, extra); rc >= 0) return rc;
  if (pos.size() != 1) {
    std::fprintf(stderr, "luxel %s: exactly one BAKE id is required\n%s", cmd, usage);
    return kExitUsage;
  }
  auto conn = Connection::open(cmd, copt);
  if (!conn) return kExitUsage;
  grpc::ClientContext ctx;
  conn->prepare_unary(ctx);
  luxel::v1::BakeInfo info;
  if (auto st = call(*conn, ctx, pos[0], info); !st.ok()) return conn->fail(cmd, st);
  if (copt.json)
    print_json_line(to_json(info));
  else
    print_bake_info(info);
  return kExitOk;
}

}  // namespace

int run_status(const std::vector<std::string>& args) {
  return bake_call("status",
                   "usage: luxel status BAKE [connection options]\n"
                   "  state, progress, ETA, features and artifacts of a bake\n",
                   args,
                   [](Connection& c, grpc::ClientContext& ctx, const std::string& id,
                      luxel::v1::BakeInfo& info) {
                     luxel::v1::GetBakeRequest req;
                     req.set_bake_id(id);
                     return c.stub().GetBake(&ctx, req, &info);
                   });
}

int run_cancel(const std::vector<std::string>& args) {
  bool finish = false;
  return bake_call(
      "cancel",
      "usage: luxel cancel BAKE [--finish] [connection options]\n"
      "  cancels a queued or running bake (a finished one is left as it is); returns\n"
      "  at once, and a running bake ends CANCELLED within a fraction of a second\n"
      "  (luxel watch BAKE waits for it);\n"
      "  --finish: stop tracing and complete the bake from the samples it has\n"
      "  (SUCCEEDED, termination \"stopped\"; results download as usual)\n",
      args,
      [&](Connection& c, grpc::ClientContext& ctx, const std::string& id,
          luxel::v1::BakeInfo& info) {
        luxel::v1::CancelBakeRequest req;
        req.set_bake_id(id);
        req.set_finish(finish);
        return c.stub().CancelBake(&ctx, req, &info);
      },
      [&](const std::vector<std::string>& a, size_t& i) {
        if (a[i] != "--finish") return false;
        finish = true;
        return true;
      });
}

int run_list(const std::vector<std::string>& args) {
  static const char* kUsage =
      "usage: luxel list [--state S]... [connection options]\n"
      "       luxel list --scenes [connection options]\n"
      "  lists bakes (optionally only those in state S: queued, running, succeeded,\n"
      "  failed, cancelled, interrupted; repeat or separate with commas) or scenes;\n"
      "  with --json one object (BakeInfo or SceneInfo) per line\n";
  ConnectionOptions copt = default_connection_options();
  std::vector<std::string> pos;
  bool scenes = false;
  bool bad_state = false;
  luxel::v1::ListBakesRequest bakes_req;
  auto extra = [&](const std::vector<std::string>& a, size_t& i) {
    if (a[i] == "--scenes") return scenes = true;
    if (a[i] != "--state" || i + 1 >= a.size()) return false;
    std::stringstream list(a[++i]);
    for (std::string item; std::getline(list, item, ',');) {
      luxel::v1::BakeState s;
      if (!parse_state(item, s)) {
        std::fprintf(stderr, "luxel list: unknown bake state '%s'\n", item.c_str());
        bad_state = true;
      }
      bakes_req.add_states(s);
    }
    return true;
  };
  if (int rc = parse_common("list", kUsage, args, copt, pos, extra); rc >= 0) return rc;
  if (bad_state) return kExitUsage;
  if (!pos.empty()) {
    std::fprintf(stderr, "luxel list: unexpected argument '%s'\n", pos[0].c_str());
    return kExitUsage;
  }
  if (scenes && bakes_req.states_size() > 0) {
    std::fprintf(stderr, "luxel list: --state applies to bakes, not to --scenes\n");
    return kExitUsage;
  }
  auto conn = Connection::open("list", copt);
  if (!conn) return kExitUsage;
  grpc::ClientContext ctx;
  conn->prepare_unary(ctx);
  if (scenes) {
    luxel::v1::ListScenesResponse resp;
    if (auto st = conn->stub().ListScenes(&ctx, {}, &resp); !st.ok()) return conn->fail("list", st);
    if (!copt.json)
      print_scene_table(resp);
    else
      for (const auto& s : resp.scenes()) print_json_line(to_json(s));
    return kExitOk;
  }
  luxel::v1::ListBakesResponse resp;
  if (auto st = conn->stub().ListBakes(&ctx, bakes_req, &resp); !st.ok())
    return conn->fail("list", st);
  if (!copt.json)
    print_bake_table(resp);
  else
    for (const auto& b : resp.bakes()) print_json_line(to_json(b));
  return kExitOk;
}

}  // namespace luxel::cli
