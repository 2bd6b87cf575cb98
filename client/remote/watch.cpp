// `luxel watch BAKE [--snapshots DIR]` and the watch loop `luxel bake` uses.
#include "remote/watch.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "commands.h"
#include "common/atomic_file.h"
#include "common/status.h"
#include "remote/output.h"

namespace luxel::cli::remote {
namespace {

class EventPrinter {
 public:
  explicit EventPrinter(const WatchOptions& o) : o_(o), tty_(isatty(fileno(stdout)) != 0) {}
  ~EventPrinter() { end_line(); }

  grpc::Status print(luxel::v1::BakeEvent& event) {
    std::string snapshot_file;
    if (event.has_snapshot() && !event.snapshot().data().empty() && !o_.snapshots_dir.empty()) {
      if (auto st = save_snapshot(event.snapshot(), snapshot_file); !st.ok()) return st;
    }
    if (o_.json) {
      // The image bytes would be megabytes of base64; scripts get the file.
      if (event.has_snapshot()) event.mutable_snapshot()->clear_data();
      nlohmann::json line = to_json(event);
      line["type"] = "event";
      if (!snapshot_file.empty()) line["snapshot_file"] = snapshot_file;
      print_json_line(line);
      return grpc::Status::OK;
    }
    if (o_.quiet) return grpc::Status::OK;
    if (!layout_shown_ && !event.info().lightmap_layout().empty()) {
      end_line();
      std::printf("uv         %s\n", event.info().lightmap_layout().c_str());
      layout_shown_ = true;
    }
    if (!snapshot_file.empty()) {
      end_line();
      std::printf("snapshot   %s (%ux%u%s)\n", snapshot_file.c_str(), event.snapshot().width(),
                  event.snapshot().height(),
                  event.snapshot().pages() > 1
                      ? strprintf(", %u pages stacked", event.snapshot().pages()).c_str()
                      : "");
    }
    // Snapshot events repeat the progress of the last progress event; in a
    // log (not a terminal) print a line only when something changed.
    const std::string now =
        event.info().progress().SerializeAsString() + state_name(event.info().state());
    if (tty_ || now != last_drawn_) {
      draw_progress_bar(progress_view(event.info().progress()), tty_,
                        strprintf("%-9s", state_name(event.info().state()).c_str()));
      last_drawn_ = now;
    }
    bar_open_ = tty_;
    return grpc::Status::OK;
  }

  void end_line() {
    if (bar_open_) std::printf("\n");
    bar_open_ = false;
  }

 private:
  grpc::Status save_snapshot(const luxel::v1::Snapshot& s, std::string& path) {
    const char* ext = s.format() == luxel::v1::SNAPSHOT_FORMAT_EXR ? "exr" : "png";
    path = (std::filesystem::path(o_.snapshots_dir) / strprintf("snapshot_%04d.%s", next_++, ext))
               .string();
    // Atomic, so an editor polling the folder never reads half an image.
    Status st = write_file_atomic(path, s.data().data(), s.data().size());
    if (!st.is_ok()) return {grpc::StatusCode::INTERNAL, st.message()};
    return grpc::Status::OK;
  }

  const WatchOptions& o_;
  const bool tty_;
  bool bar_open_ = false;
  std::string last_drawn_;
  bool layout_shown_ = false;
  int next_ = 0;
};

}  // namespace

grpc::Status watch_bake(Connection& conn, const std::string& bake_id, const WatchOptions& options,
                        luxel::v1::BakeInfo& final_info) {
  if (!options.snapshots_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.snapshots_dir, ec);
    if (ec)
      return {grpc::StatusCode::INVALID_ARGUMENT,
              "cannot create --snapshots folder '" + options.snapshots_dir + "': " + ec.message()};
  }
  EventPrinter printer(options);
  luxel::v1::WatchBakeRequest req;
  req.set_bake_id(bake_id);
  auto give_up_at = std::chrono::steady_clock::time_point::max();
  bool announced = false;
  for (;;) {
    grpc::ClientContext ctx;
    conn.prepare_stream(ctx);
    auto reader = conn.stub().WatchBake(&ctx, req);
    luxel::v1::BakeEvent event;
    bool got_event = false;
    while (reader->Read(&event)) {
      got_event = true;
      give_up_at = std::chrono::steady_clock::time_point::max();
      if (auto st = printer.print(event); !st.ok()) {
        ctx.TryCancel();
        (void)reader->Finish();
        return st;
      }
      if (event.final()) {
        final_info = event.info();
        ctx.TryCancel();  // the daemon ends the stream; do not wait on it
        (void)reader->Finish();
        return grpc::Status::OK;
      }
    }
    grpc::Status st = reader->Finish();
    if (st.ok())
      st = {grpc::StatusCode::ABORTED,
            "the watch stream of bake " + bake_id + " ended before the bake finished"};
    // A daemon restart breaks the stream (UNAVAILABLE, or CANCELLED / an
    // early end while it shuts down); the daemon resumes the bake after it.
    const auto code = st.error_code();
    const bool in_outage = give_up_at != std::chrono::steady_clock::time_point::max();
    const bool retryable = code == grpc::StatusCode::UNAVAILABLE ||
                           code == grpc::StatusCode::CANCELLED || code == grpc::StatusCode::ABORTED;
    if (!retryable || !(got_event || in_outage) || options.reconnect_s <= 0) return st;
    const auto now = std::chrono::steady_clock::now();
    if (!in_outage) {
      give_up_at = now + std::chrono::seconds(options.reconnect_s);
      if (!announced) {
        printer.end_line();
        std::fprintf(stderr, "luxel: lost luxeld at %s (%s: %s); reconnecting for up to %d s\n",
                     conn.options().server.c_str(), status_code_name(code),
                     st.error_message().c_str(), options.reconnect_s);
        announced = true;
      }
    } else if (now >= give_up_at) {
      return st;
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
}

int bake_outcome(const char* cmd, const luxel::v1::BakeInfo& info) {
  if (info.state() == luxel::v1::BAKE_STATE_SUCCEEDED) return kExitOk;
  std::string why = info.error_message();
  if (info.state() == luxel::v1::BAKE_STATE_INTERRUPTED && why.empty())
    why = "the daemon stopped during the bake; it resumes from its checkpoint when luxeld restarts";
  std::fprintf(stderr, "luxel %s: bake %s %s%s%s\n", cmd, info.bake_id().c_str(),
               state_name(info.state()).c_str(), why.empty() ? "" : ": ", why.c_str());
  return kExitBakeFailed;
}

}  // namespace luxel::cli::remote

namespace luxel::cli {

int run_watch(const std::vector<std::string>& args) {
  using namespace remote;
  static const char* kUsage =
      "usage: luxel watch BAKE [--snapshots DIR] [--quiet] [connection options]\n"
      "  follows a bake until it ends (exit 0 SUCCEEDED, 3 FAILED/CANCELLED/INTERRUPTED)\n"
      "  --snapshots DIR       write each progressive snapshot to DIR/snapshot_NNNN.png (.exr)\n"
      "  --quiet               no progress bar\n";
  ConnectionOptions copt = default_connection_options();
  WatchOptions wopt;
  std::string bake_id;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& k = args[i];
    const OptionMatch m = take_connection_option("watch", args, i, copt);
    if (m == OptionMatch::kError) return kExitUsage;
    if (m == OptionMatch::kTaken) continue;
    if (k == "--help" || k == "-h") {
      std::printf("%s%s", kUsage, kConnectionUsage);
      return kExitOk;
    }
    if (k == "--snapshots" && i + 1 < args.size())
      wopt.snapshots_dir = args[++i];
    else if (k == "--quiet")
      wopt.quiet = true;
    else if (!k.empty() && k[0] == '-') {
      std::fprintf(stderr, "luxel watch: unknown option or missing value '%s'\n%s", k.c_str(),
                   kUsage);
      return kExitUsage;
    } else if (bake_id.empty())
      bake_id = k;
    else {
      std::fprintf(stderr, "luxel watch: unexpected argument '%s'\n", k.c_str());
      return kExitUsage;
    }
  }
  if (bake_id.empty()) {
    std::fprintf(stderr, "luxel watch: a BAKE id is required\n%s", kUsage);
    return kExitUsage;
  }
  wopt.json = copt.json;
  auto conn = Connection::open("watch", copt);
  if (!conn) return kExitUsage;
  luxel::v1::BakeInfo info;
  if (auto st = watch_bake(*conn, bake_id, wopt, info); !st.ok()) return conn->fail("watch", st);
  return bake_outcome("watch", info);
}

}  // namespace luxel::cli
