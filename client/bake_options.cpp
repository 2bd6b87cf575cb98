#include "bake_options.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "commands.h"
#include "scene/import_budget.h"
#include "settings/settings_schema.h"

namespace luxel::cli {
namespace {

using pipeline::Setting;
using pipeline::SettingScope;

const char* kUsageHead =
    "usage: luxel bake SCENE --out DIR [options]            (on a luxeld daemon)\n"
    "       luxel bake SCENE --local --out DIR [options]    (in this process)\n";

const char* kRemoteOptions =
    "  --snapshots DIR          write each snapshot to DIR/snapshot_NNNN.png while watching\n"
    "  --idempotency-key K      a retry with the same key returns the same bake\n"
    "  --name NAME              scene display name when it is uploaded\n"
    "  --detach                 print the bake id after submitting and return\n"
    "  (and the connection options of `luxel upload --help`)\n"
    "exit codes: 0 done, 1 error (daemon, network, files), 2 usage, 3 bake failed/cancelled\n";

const char* kLocalOptions =
    "  --device SPEC            OpenCL device (see `luxel devices`)\n"
    "  --host-memory-budget N   refuse a bake estimated to need more host bytes (default half\n"
    "                           the machine's memory or the cgroup's memory.max; 0 = no check)\n";

// "  --bounces B              indirect bounces ... (default 4)", wrapped at 100 columns.
std::string option_help(const Setting& st) {
  std::string metavar = st.metavar ? st.metavar : "";
  if (st.type == pipeline::SettingType::kChoice) {
    metavar.clear();
    for (const char* c : st.choices) metavar += (metavar.empty() ? "" : "|") + std::string(c);
  }
  std::string left = std::string("  ") + st.flag + (metavar.empty() ? "" : " " + metavar);
  std::string text = st.help;
  if (st.type == pipeline::SettingType::kChoiceList)
    text += ", comma-separated: " + pipeline::describe_range(st);
  if (*st.units) text += std::string(" [") + st.units + "]";
  if (st.type != pipeline::SettingType::kBool) {
    const std::string d = pipeline::format_setting_value(st, st.default_value);
    text += " (default " + (d.empty() ? std::string("none") : d) + ")";
  }
  constexpr size_t kColumn = 27, kWidth = 100;
  std::string out = left;
  out += left.size() + 1 < kColumn ? std::string(kColumn - left.size(), ' ')
                                   : "\n" + std::string(kColumn, ' ');
  size_t col = kColumn;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find(' ', start);
    if (end == std::string::npos) end = text.size();
    const std::string word = text.substr(start, end - start);
    if (col > kColumn && col + 1 + word.size() > kWidth) {
      out += "\n" + std::string(kColumn, ' ');
      col = kColumn;
    } else if (col > kColumn) {
      out += ' ';
      ++col;
    }
    out += word;
    col += word.size();
    start = end + 1;
  }
  return out + "\n";
}

std::string usage() {
  std::string u = kUsageHead;
  const struct {
    SettingScope scope;
    const char* title;
  } sections[] = {
      {SettingScope::kEverywhere, "settings (luxel settings lists their ranges):\n"},
      {SettingScope::kApiOnly,
       "remote (default; SCENE may also be the id of a scene the daemon stores):\n"},
      {SettingScope::kLocalOnly, "--local only:\n"},
  };
  for (const auto& section : sections) {
    u += section.title;
    for (const Setting& st : pipeline::settings_schema())
      if (st.flag && st.scope == section.scope) u += option_help(st);
    if (section.scope == SettingScope::kApiOnly) u += kRemoteOptions;
    if (section.scope == SettingScope::kLocalOnly) u += kLocalOptions;
  }
  u += "  --quiet                  no progress bar\n";
  return u;
}

const Setting* setting_for_flag(const std::string& flag) {
  for (const Setting& st : pipeline::settings_schema())
    if (st.flag && flag == st.flag) return &st;
  return nullptr;
}

bool is_remote_only(const std::string& k) {
  for (const char* o : {"--snapshots", "--idempotency-key", "--name", "--detach", "--server",
                        "--token", "--tls-ca", "--tls", "--timeout", "--json"})
    if (k == o) return true;
  return false;
}

}  // namespace

ParseOutcome parse_bake_args(const std::vector<std::string>& args, BakeCommand& a) {
  a.settings = pipeline::default_settings();
  a.connection = remote::default_connection_options();
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& k = args[i];
    if (is_remote_only(k)) a.remote_only.push_back(k);
    if (k == "--device" || k == "--host-memory-budget") a.local_only.push_back(k);
    const auto m = remote::take_connection_option("bake", args, i, a.connection);
    if (m == remote::OptionMatch::kError) return ParseOutcome::kUsageError;
    if (m == remote::OptionMatch::kTaken) continue;
    auto value = [&]() -> const char* {
      if (i + 1 >= args.size()) {
        std::fprintf(stderr, "luxel bake: %s needs a value\n", k.c_str());
        return nullptr;
      }
      return args[++i].c_str();
    };
    auto text = [&](std::string& out) -> bool {
      const char* v = value();
      if (v) out = v;
      return v != nullptr;
    };
    bool ok = true;
    if (k == "--help" || k == "-h") {
      std::printf("%s%s", usage().c_str(), remote::kConnectionUsage);
      return ParseOutcome::kHelpShown;
    }
    if (k == "--local")
      a.local = true;
    else if (k == "--quiet")
      a.quiet = true;
    else if (k == "--detach")
      a.detach = true;
    else if (k == "--out")
      ok = text(a.out);
    else if (k == "--device")
      ok = text(a.device);
    else if (k == "--host-memory-budget") {
      // Byte sizes as luxeld takes them ("8GiB", "8e9"); 0: no check.
      std::string v;
      ok = text(v);
      auto bytes = ok ? scene::parse_byte_size(v) : Result<uint64_t>(0);
      if (ok && !bytes) {
        std::fprintf(stderr, "luxel bake: --host-memory-budget: %s\n",
                     bytes.status().message().c_str());
        ok = false;
      }
      if (ok) a.host_memory_budget = static_cast<double>(*bytes);
    } else if (k == "--name")
      ok = text(a.name);
    else if (k == "--snapshots")
      ok = text(a.snapshots_dir);
    else if (k == "--idempotency-key")
      ok = text(a.idempotency_key);
    else if (k == "--shards" && i + 1 < args.size() && args[i + 1] == "auto") {
      // The one setting whose option takes a word besides a number: "auto" is
      // settings.shards_auto (one shard per worker the coordinator resolves).
      a.remote_only.push_back(k);
      a.settings.job.shards_auto = true;
      a.settings.adaptive = false;  // as --shards N > 1 implies
      ++i;
    } else if (const Setting* st = setting_for_flag(k)) {
      if (st->scope == SettingScope::kLocalOnly) a.local_only.push_back(k);
      if (st->scope == SettingScope::kApiOnly) a.remote_only.push_back(k);
      // A switch turns its setting away from the default (--no-compaction).
      Result<pipeline::SettingValue> v = pipeline::SettingValue::of(st->default_value.number == 0);
      if (st->type != pipeline::SettingType::kBool) {
        const char* given = value();
        if (!given) return ParseOutcome::kUsageError;
        v = pipeline::parse_setting_value(*st, given);
      }
      Status applied = v ? pipeline::apply_setting(a.settings, *st, v.value()) : v.status();
      if (!applied.is_ok()) {
        std::fprintf(stderr, "luxel bake: %s (%s)\n", applied.message().c_str(), k.c_str());
        ok = false;
      } else if (st->implies) {
        st->implies(a.settings);
      }
    } else if (!k.empty() && k[0] == '-') {
      std::fprintf(stderr, "luxel bake: unknown option '%s' (luxel bake --help)\n", k.c_str());
      ok = false;
    } else if (a.scene.empty())
      a.scene = k;
    else {
      std::fprintf(stderr, "luxel bake: unexpected argument '%s'\n", k.c_str());
      ok = false;
    }
    if (!ok) return ParseOutcome::kUsageError;
  }
  if (a.scene.empty() || (a.out.empty() && !a.detach)) {
    std::fprintf(stderr, "luxel bake: a SCENE and --out DIR are required (luxel bake --help)\n");
    return ParseOutcome::kUsageError;
  }
  return ParseOutcome::kOk;
}

int run_settings(const std::vector<std::string>& args) {
  bool json = false;
  for (const auto& a : args) {
    if (a == "--json")
      json = true;
    else {
      std::fprintf(
          a == "--help" ? stdout : stderr,
          "usage: luxel settings [--json]\n"
          "  every bake setting: name (the field path in errors and in the API), CLI\n"
          "  option, default, range, units, where it applies; --json: the schema as JSON\n");
      return a == "--help" ? 0 : 2;
    }
  }
  if (json) {
    std::fputs(pipeline::settings_schema_json().c_str(), stdout);
    return 0;
  }
  static const char* kScopes[] = {"", "local only", "daemon only"};
  for (const Setting& st : pipeline::settings_schema()) {
    std::printf("settings.%s%s%s\n", st.name, st.flag ? "  " : "", st.flag ? st.flag : "");
    std::printf("    %s\n", st.help);
    std::printf("    default %s; %s%s%s%s%s\n",
                pipeline::format_setting_value(st, st.default_value).c_str(),
                pipeline::describe_range(st).c_str(), *st.units ? "; " : "", st.units,
                st.scope == SettingScope::kEverywhere ? "" : "; ",
                kScopes[static_cast<int>(st.scope)]);
    if (st.in_api() && st.api_note) std::printf("    API: %s\n", st.api_note);
  }
  return 0;
}

bool read_probe_positions(BakeCommand& a) {
  if (a.settings.probes.rfind("file:", 0) != 0 || !a.settings.probe_positions.empty()) return true;
  const std::string file = a.settings.probes.substr(5);
  std::ifstream f(file, std::ios::binary);
  std::stringstream text;
  text << f.rdbuf();
  if (!f) {
    std::fprintf(stderr, "luxel bake: --probes: cannot read %s\n", file.c_str());
    return false;
  }
  a.settings.probe_positions = text.str();
  return true;
}

}  // namespace luxel::cli
