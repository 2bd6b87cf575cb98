// luxel: the Luxel command-line client.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "commands.h"
#include "luxel_version.h"

namespace {

void usage(FILE* out) {
  std::fprintf(out,
               "luxel %s (%s): lightmap baker\n\n"
               "usage: luxel <command> [options]\n\n"
               "commands:\n",
               LUXEL_VERSION, LUXEL_GIT_REVISION);
#define LUXEL_CLI_USAGE(name, function, group, text) \
  if (group == 0) std::fputs(text, out);
  LUXEL_CLI_COMMANDS(LUXEL_CLI_USAGE)
  std::fputs("\ncommands on a luxeld daemon (each: --help for its options):\n", out);
#undef LUXEL_CLI_USAGE
#define LUXEL_CLI_USAGE(name, function, group, text) \
  if (group == 1) std::fputs(text, out);
  LUXEL_CLI_COMMANDS(LUXEL_CLI_USAGE)
#undef LUXEL_CLI_USAGE
  std::fputs(
      "  common options: --server HOST:PORT (default $LUXEL_SERVER or 127.0.0.1:50051),\n"
      "        --token T ($LUXEL_TOKEN), --tls-ca FILE, --tls, --timeout S, --json\n\n"
      "exit codes: 0 success, 1 error (daemon, network, files), 2 usage error,\n"
      "            3 the bake failed, was cancelled or interrupted\n",
      out);
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // progress lines appear as they are printed
  if (argc < 2) {
    usage(stderr);
    return 2;
  }
  const std::string cmd = argv[1];
  std::vector<std::string> args(argv + 2, argv + argc);
  if (cmd == "-h" || cmd == "--help" || cmd == "help") {
    usage(stdout);
    return 0;
  }
  if (cmd == "--version") {
    std::printf("luxel %s (%s)\n", LUXEL_VERSION, LUXEL_GIT_REVISION);
    return 0;
  }
#define LUXEL_CLI_DISPATCH(name, function, group, text) \
  if (name != nullptr && cmd == static_cast<const char*>(name)) return luxel::cli::function(args);
  LUXEL_CLI_COMMANDS(LUXEL_CLI_DISPATCH)
#undef LUXEL_CLI_DISPATCH
  std::fprintf(stderr, "luxel: unknown command '%s'\n\n", cmd.c_str());
  usage(stderr);
  return 2;
}
