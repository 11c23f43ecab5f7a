// `tetraprobe merge PART... -o LEVEL.tpb`: joins the part files of a sharded bake into the level the
// one-process bake with the same options gives, byte for byte (docs/distributed.md). Checks the parts first:
// same scene, same options, same shard count, every shard exactly once, the same floor; then runs the bake's
// serial stages (placement again, bake pass 3, tetrahedralization, occlusion, hole rounds, refinement).
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "args.h"
#include "commands.h"
#include "shard_part.h"
#include "tetraprobe/common/error.h"
#include "trace_farm.h"

namespace tetraprobe::cli {

int cmdMerge(int argc, char** argv) {
  Args args(
      "tetraprobe merge PART... -o LEVEL.tpb [options]",
      "Joins the part files of a sharded bake (tetraprobe bake --shard I/N ... -o PART) into one level,\n"
      "bit-identical to the one-process bake with the same options. Re-reads the scene the parts name\n"
      "(it must be unchanged) and runs the stages that need every probe (docs/distributed.md).",
      {{"--output", "-o", "LEVEL.tpb", "level file to write", ""},
       {"--report", "", "FILE.json", "also write a JSON report of the bake", ""},
       {"--threads", "", "N", "worker threads, 0 = all cores (never changes the output)", "0"},
       {"--farm", "", "DIR",
        "hand the merge's tracing (the probes its rounds add, the path budget) to `tetraprobe worker` "
        "processes through this directory (shared by every process; empty or new)",
        ""},
       {"--workers", "", "N", "with --farm: the number of workers (each started with --index I/N)", "0"},
       {"--farm-timeout", "", "SECONDS",
        "with --farm: stop when a worker gives no sign of life for this long",
        std::to_string(int(kFarmDefaultTimeout))},
       {"--floor", "", "",
        "two-round protocol: join round-1 parts (bake --round 1) into the floor part that round 2 "
        "(bake --round 2 --floor FILE) needs, instead of a level",
        ""}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(1, 1 << 16);
  if (!args.has("--output")) throw UsageError("missing -o LEVEL.tpb");

  std::vector<ShardPart> parts;
  for (const std::string& path : args.positional()) parts.push_back(readShardPart(path));
  if (args.has("--floor")) {
    // Between the rounds of the two-round protocol: the floor over every probe's pass-1 mean.
    checkShardSet(parts, args.positional(), PartStage::kPass1);
    std::vector<double> means;
    for (const ShardPart& p : parts)
      for (const ProbeBakeState& st : p.bake.states) means.push_back(probeBakeMean(st));
    ShardPart floor = parts[0];
    floor.stage = PartStage::kFloor;
    floor.index = 0;
    floor.bake = ShardBake{};
    floor.bake.floor = bakeErrorFloor(std::move(means));
    writeShardPart(args.str("--output"), floor);
    std::printf("tetraprobe merge: floor %.9g from the pass-1 means of %zu shards -> %s\n", floor.bake.floor,
                parts.size(), args.str("--output").c_str());
    return 0;
  }
  checkShardSet(parts, args.positional(), PartStage::kPass12);
  const ShardPart& first = parts[0];
  MergedShards merged;
  if (args.has("--farm")) {
    const int workers = args.integer("--workers");
    const double timeout = args.number("--farm-timeout");
    if (workers < 1 || workers > 65536)
      throw UsageError("--farm needs --workers N, an integer from 1 to 65536");
    if (!(timeout > 0.0)) throw UsageError("--farm-timeout must be > 0");
    merged.farmDir = args.str("--farm");
    merged.farmWorkers = workers;
    merged.farmTimeout = timeout;
  } else if (args.has("--workers")) {
    throw UsageError("--workers needs --farm DIR");
  }
  merged.sceneHash = first.sceneHash;
  merged.probeCount = first.probeCount;
  merged.bake.floor = first.bake.floor;
  for (const ShardPart& p : parts) {
    merged.bake.probes.insert(merged.bake.probes.end(), p.bake.probes.begin(), p.bake.probes.end());
    merged.bake.states.insert(merged.bake.states.end(), p.bake.states.begin(), p.bake.states.end());
  }

  // The bake's own command line, from the canonical options the shards recorded.
  std::vector<std::string> line;
  size_t start = 0;
  for (size_t end; (end = first.options.find('\n', start)) != std::string::npos; start = end + 1)
    line.push_back(first.options.substr(start, end - start));
  if (line.empty() || start != first.options.size())
    throw InputError("shard part " + args.positional()[0] + ": malformed options");
  line.push_back("--output=" + args.str("--output"));
  line.push_back("--threads=" + args.str("--threads"));
  if (args.has("--report")) line.push_back("--report=" + args.str("--report"));
  std::vector<char*> argvOut;
  for (std::string& s : line) argvOut.push_back(s.data());
  return runBake(int(argvOut.size()), argvOut.data(), &merged);
}

}  // namespace tetraprobe::cli
