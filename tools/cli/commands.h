// The tetraprobe subcommands. Each takes the arguments after its name and returns the process exit code;
// errors propagate as exceptions that main() maps to exit codes (usage/input -> 2, other -> 1).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace tetraprobe::cli {

struct MergedShards;
int cmdBake(int argc, char** argv);
// `bake` itself; with `merge` (from `tetraprobe merge`), the shards' probe states replace bake passes 1-2.
int runBake(int argc, char** argv, const MergedShards* merge);
int cmdMerge(int argc, char** argv);
int cmdWorker(int argc, char** argv);
int cmdStream(int argc, char** argv);
int cmdInspect(int argc, char** argv);
int cmdQuery(int argc, char** argv);
int cmdRender(int argc, char** argv);
int cmdEval(int argc, char** argv);
int cmdReference(int argc, char** argv);
int cmdExportSh(int argc, char** argv);
int cmdBench(int argc, char** argv);
int benchLocate(int argc, char** argv);  // `bench locate` (bench_locate.cpp)
int benchRender(int argc, char** argv);  // `bench render` (bench_render.cpp)
int cmdDiff(int argc, char** argv);

// Writes a JSON report atomically (2-space indent, trailing newline); throws on failure.
void writeJsonReport(const std::string& path, const nlohmann::json& report);

}  // namespace tetraprobe::cli
