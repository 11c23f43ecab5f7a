// tetraprobe: the per-level build tool and its companions (inspect, query, render, eval).
// Exit codes: 0 success, 1 failure, 2 bad usage or bad input. Errors are one line on stderr.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "args.h"
#include "commands.h"
#include "tetraprobe/common/error.h"

namespace {

struct Command {
  const char* name;
  int (*run)(int, char**);
  const char* summary;
};

constexpr Command kCommands[] = {
    {"bake", tetraprobe::cli::cmdBake, "place probes, path-trace their SH, tetrahedralize, write LEVEL.tpb"},
    {"merge", tetraprobe::cli::cmdMerge,
     "join the part files of a sharded bake (bake --shard I/N) into LEVEL.tpb"},
    {"worker", tetraprobe::cli::cmdWorker,
     "trace a share of a merge's probes (merge --farm DIR --workers N)"},
    {"stream", tetraprobe::cli::cmdStream, "add a streaming index (sectors + coarse probe set) to a level"},
    {"inspect", tetraprobe::cli::cmdInspect, "print what a level file holds"},
    {"query", tetraprobe::cli::cmdQuery, "irradiance at points, from the level file (CPU runtime)"},
    {"render", tetraprobe::cli::cmdRender, "render a view lit per pixel by the probes (Vulkan, headless)"},
    {"eval", tetraprobe::cli::cmdEval, "measure lookup error against path-traced ground truth"},
    {"reference", tetraprobe::cli::cmdReference, "path-traced irradiance at points, to a target error"},
    {"export-sh", tetraprobe::cli::cmdExportSh,
     "write a level's probes and SH as CSV (for bake --import-sh)"},
    {"bench", tetraprobe::cli::cmdBench, "throughput against a peer in the same run (bench bake)"},
    {"diff", tetraprobe::cli::cmdDiff, "compare two images for visual regression (exit 1 when they differ)"},
};

void printUsage(std::FILE* out) {
  std::fprintf(out,
               "usage: tetraprobe COMMAND [ARGS...]   (tetraprobe COMMAND --help for its options)\n\n"
               "Tetrahedral irradiance probes: bake a level, then query and render it.\n\ncommands:\n");
  for (const auto& c : kCommands) std::fprintf(out, "  %-9s %s\n", c.name, c.summary);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    printUsage(stderr);
    return 2;
  }
  const std::string name = argv[1];
  if (name == "--help" || name == "-h" || name == "help") {
    printUsage(stdout);
    return 0;
  }
  if (name == "--version") {
    std::printf("tetraprobe 0.1.0\n");
    return 0;
  }
  for (const auto& c : kCommands) {
    if (name != c.name) continue;
    try {
      return c.run(argc - 2, argv + 2);
    } catch (const tetraprobe::cli::UsageError& e) {
      std::fprintf(stderr, "tetraprobe %s: error: %s\n", c.name, e.what());
      return 2;
    } catch (const tetraprobe::InputError& e) {
      std::fprintf(stderr, "tetraprobe %s: error: %s\n", c.name, e.what());
      return 2;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "tetraprobe %s: failed: %s\n", c.name, e.what());
      return 1;
    }
  }
  std::string names;
  for (const auto& c : kCommands) names += std::string(names.empty() ? "" : ", ") + c.name;
  std::fprintf(stderr, "tetraprobe: error: unknown command '%s' (commands: %s)\n", name.c_str(),
               names.c_str());
  return 2;
}
