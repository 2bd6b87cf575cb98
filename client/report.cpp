// `luxel report`: the error-against-time series of a bake as a
// table, a CSV file or a log-log plot. The series comes from a local output
// folder (`luxel bake --local --out DIR`, `luxel fetch`) or from a finished
// bake on luxeld (downloaded with sha256 checks).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "commands.h"
#include "common/atomic_file.h"
#include "common/status.h"
#include "output/manifest.h"
#include "remote/connection.h"
#include "remote/fetch.h"
#include "remote/output.h"

namespace luxel::cli {
namespace {

namespace fs = std::filesystem;

const char* kUsage =
    "usage: luxel report DIR|BAKE [--csv FILE] [--plot FILE.png] [--all] [connection options]\n"
    "  prints a bake's error against time: elapsed seconds, paths, mean and minimum samples\n"
    "  per texel, the reference-free error estimate (mean relative standard error) and,\n"
    "  when the bake had a reference, RMSE and relMSE against it.\n"
    "  DIR: a folder written by `luxel bake` or `luxel fetch`; BAKE: a finished bake on luxeld.\n"
    "  --csv FILE       also write the series as CSV\n"
    "  --plot FILE.png  log-log plot of the errors against time (python3-matplotlib)\n"
    "  --all            every row (default: at most 25, evenly spaced, and the last)\n";

struct Row {
  double elapsed = 0, mean_spp = 0, error = 0, rmse = -1, rel_mse = -1;
  unsigned long long paths = 0;
  unsigned min_spp = 0;
};

Result<std::vector<Row>> parse_series(const std::string& csv, const std::string& what) {
  std::istringstream in(csv);
  std::string line;
  if (!std::getline(in, line) || line.rfind("elapsed_s,paths,mean_spp,min_spp,rel_error", 0) != 0)
    return invalid_argument(what + ": not a Luxel error series (header missing)");
  std::vector<Row> rows;
  int n = 1;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    Row r;
    char rmse[64] = "", rel[64] = "";
    const int got = std::sscanf(line.c_str(), "%lf,%llu,%lf,%u,%lf,%63[^,],%63s", &r.elapsed,
                                &r.paths, &r.mean_spp, &r.min_spp, &r.error, rmse, rel);
    if (got < 5)
      return invalid_argument(
          strprintf("%s: line %d is malformed: '%s'", what.c_str(), n, line.c_str()));
    if (got >= 7) {
      r.rmse = std::atof(rmse);
      r.rel_mse = std::atof(rel);
    }
    rows.push_back(r);
  }
  return rows;
}

std::string read_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// The plotting script (matplotlib, Agg backend): argv = csv png title.
const char* kPlotScript = R"PY(
import csv, sys, math
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
rows = list(csv.DictReader(open(sys.argv[1])))
t = [float(r["elapsed_s"]) for r in rows]
def series(key, f=lambda x: x):
    pts = [(ti, f(float(r[key]))) for ti, r in zip(t, rows) if r.get(key) not in (None, "") and ti > 0]
    return [p for p in pts if p[1] > 0]
fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=110)
for key, label, f in (("rel_error", "estimate (mean rel. std. error)", lambda x: x),
                      ("rmse", "RMSE vs reference", lambda x: x),
                      ("rel_mse", "sqrt(relMSE) vs reference", math.sqrt)):
    pts = series(key, f)
    if pts:
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker=".", label=label)
if len(t) > 1 and t[-1] > 0 and float(rows[-1]["rel_error"]) > 0:
    t0, e0 = t[-1], float(rows[-1]["rel_error"])
    ax.loglog([t0 / 16, t0], [e0 * 4, e0], "k:", linewidth=0.8, label="slope -1/2")
ax.set_xlabel("tracing time (s)")
ax.set_ylabel("error")
ax.set_title(sys.argv[3])
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(sys.argv[2])
)PY";

int plot(const std::string& csv_path, const std::string& png, const std::string& title) {
  const std::string script =
      (fs::temp_directory_path() / strprintf("luxel_plot_%d.py", getpid())).string();
  std::ofstream(script) << kPlotScript;
  auto quote = [](const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  // Debian's python3 (where python3-matplotlib lives) before whatever
  // python3 is first on PATH; LUXEL_PYTHON overrides both.
  std::string python = "python3";
  if (const char* env = std::getenv("LUXEL_PYTHON"); env && *env)
    python = env;
  else if (fs::exists("/usr/bin/python3"))
    python = "/usr/bin/python3";
  const std::string cmd = quote(python) + " " + quote(script) + " " + quote(csv_path) + " " +
                          quote(png) + " " + quote(title);
  const int rc = std::system(cmd.c_str());
  fs::remove(script);
  if (rc != 0) {
    std::fprintf(stderr,
                 "luxel report: plotting failed (python3 with matplotlib is needed: "
                 "deploy/install-deps.sh installs python3-matplotlib)\n");
    return 1;
  }
  std::printf("wrote      %s\n", png.c_str());
  return 0;
}

}  // namespace

int run_report(const std::vector<std::string>& args) {
  using namespace remote;
  ConnectionOptions copt = default_connection_options();
  std::string target, csv_out, png_out;
  bool all = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& k = args[i];
    const OptionMatch m = take_connection_option("report", args, i, copt);
    if (m == OptionMatch::kError) return 2;
    if (m == OptionMatch::kTaken) continue;
    if (k == "--help" || k == "-h") {
      std::printf("%s%s", kUsage, kConnectionUsage);
      return 0;
    }
    if (k == "--csv" && i + 1 < args.size())
      csv_out = args[++i];
    else if (k == "--plot" && i + 1 < args.size())
      png_out = args[++i];
    else if (k == "--all")
      all = true;
    else if (!k.empty() && k[0] == '-') {
      std::fprintf(stderr, "luxel report: unknown option or missing value '%s'\n%s", k.c_str(),
                   kUsage);
      return 2;
    } else if (target.empty())
      target = k;
    else {
      std::fprintf(stderr, "luxel report: unexpected argument '%s'\n", k.c_str());
      return 2;
    }
  }
  if (target.empty()) {
    std::fprintf(stderr, "luxel report: a DIR or BAKE id is required\n%s", kUsage);
    return 2;
  }

  // A local folder, or a bake on the daemon (its two files downloaded).
  std::string dir = target;
  std::error_code ec;
  fs::path tmp;
  if (!fs::is_directory(target, ec)) {
    auto conn = Connection::open("report", copt);
    if (!conn) return 2;
    luxel::v1::BakeInfo info;
    grpc::ClientContext ctx;
    conn->prepare_unary(ctx);
    luxel::v1::GetBakeRequest req;
    req.set_bake_id(target);
    if (auto st = conn->stub().GetBake(&ctx, req, &info); !st.ok()) return conn->fail("report", st);
    if (info.state() != luxel::v1::BAKE_STATE_SUCCEEDED) {
      std::fprintf(stderr,
                   "luxel report: bake %s is %s; its series is complete once it SUCCEEDED\n",
                   target.c_str(), state_name(info.state()).c_str());
      return 1;
    }
    tmp = fs::temp_directory_path() / strprintf("luxel_report_%d", getpid());
    dir = tmp.string();
    FetchedArtifact a;
    fs::create_directories(tmp, ec);
    for (const char* name : {"error_series.csv", "manifest.json"})
      if (auto st = download_artifact(*conn, target, name, dir, a); !st.ok()) {
        fs::remove_all(tmp, ec);
        return conn->fail("report", st);
      }
  }
  const std::string csv_path = (fs::path(dir) / "error_series.csv").string();
  if (!fs::exists(csv_path)) {
    std::fprintf(stderr, "luxel report: %s has no error_series.csv\n", dir.c_str());
    return 1;
  }
  const std::string csv = read_text(csv_path);
  auto rows = parse_series(csv, csv_path);
  auto manifest = output::read_manifest((fs::path(dir) / "manifest.json").string());
  if (!rows) {
    std::fprintf(stderr, "luxel report: %s\n", rows.status().message().c_str());
    return 1;
  }
  const std::string title = manifest ? strprintf("%s, %dx%d", manifest->scene_name.c_str(),
                                                 manifest->width, manifest->height)
                                     : target;
  std::printf("bake       %s\n", title.c_str());
  if (manifest)
    std::printf(
        "stopped by %s after %.2f s, %llu paths, error estimate %.4g%s\n",
        manifest->stats.termination.c_str(), manifest->stats.seconds,
        static_cast<unsigned long long>(manifest->stats.paths), manifest->stats.error_estimate,
        manifest->stats.rmse >= 0
            ? strprintf(", RMSE %.4g, relMSE %.4g", manifest->stats.rmse, manifest->stats.rel_mse)
                  .c_str()
            : "");
  const bool with_ref = !rows->empty() && rows->back().rmse >= 0;
  std::printf("\n%10s %12s %9s %7s %10s%s\n", "elapsed_s", "paths", "mean_spp", "min_spp",
              "estimate", with_ref ? "       rmse    rel_mse" : "");
  const size_t n = rows->size();
  const size_t step = all || n <= 25 ? 1 : (n + 24) / 25;
  for (size_t i = 0; i < n; ++i) {
    if (i % step != 0 && i + 1 != n) continue;
    const Row& r = (*rows)[i];
    std::printf("%10.3f %12llu %9.2f %7u %10.4g", r.elapsed, r.paths, r.mean_spp, r.min_spp,
                r.error);
    if (with_ref) std::printf(" %10.4g %10.4g", r.rmse, r.rel_mse);
    std::printf("\n");
  }
  int rc = 0;
  if (!csv_out.empty()) {
    if (Status st = write_file_atomic(csv_out, csv.data(), csv.size()); !st.is_ok()) {
      std::fprintf(stderr, "luxel report: %s\n", st.message().c_str());
      rc = 1;
    } else {
      std::printf("wrote      %s\n", csv_out.c_str());
    }
  }
  if (!png_out.empty() && rc == 0) rc = plot(csv_path, png_out, title);
  if (!tmp.empty()) fs::remove_all(tmp, ec);
  return rc;
}

}  // namespace luxel::cli
