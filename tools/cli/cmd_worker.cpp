// `tetraprobe worker SCENE --farm DIR --index I/N`: one worker of a merge's trace farm (trace_farm.h,
// docs/distributed.md#the-merge-farmed). Traces its share of every job the merge writes to DIR until the
// merge is done.
#include <cstdio>
#include <string>

#include "args.h"
#include "commands.h"
#include "shard_part.h"
#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/progress.h"
#include "tetraprobe/scene/load.h"
#include "trace_farm.h"

namespace tetraprobe::cli {

int cmdWorker(int argc, char** argv) {
  Args args(
      "tetraprobe worker SCENE --farm DIR --index I/N [options]",
      "One worker of a merge's trace farm (tetraprobe merge --farm DIR --workers N): traces its share\n"
      "of the probes of every step the merge hands out, until the merge writes DIR/done. SCENE must be\n"
      "the scene the shards baked. Start the N workers with the merge, in any order.",
      {{"--farm", "", "DIR", "the farm directory the merge writes (shared by every process)", ""},
       {"--index", "", "I/N", "this worker's index and the number of workers (the merge's --workers)", ""},
       {"--threads", "", "N", "worker threads, 0 = all cores (never changes the output)", "0"},
       {"--farm-timeout", "", "SECONDS", "stop when the merge gives no sign of life for this long",
        std::to_string(int(kFarmDefaultTimeout))}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(1, 1);
  if (!args.has("--farm")) throw UsageError("missing --farm DIR");
  const IndexOfCount worker = parseIndexOfCount(args.str("--index"), "--index");
  const double timeout = args.number("--farm-timeout");
  if (!(timeout > 0.0)) throw UsageError("--farm-timeout must be > 0");
  const int threads = args.integer("--threads");
  const std::string scenePath = args.positional()[0];
  const Scene scene = loadScene(scenePath);
  const SceneTracer tracer(scene);
  const int jobs = runFarmWorker(tracer, sceneContentHash(scene), args.str("--farm"), worker.index,
                                 worker.count, threads, timeout, Progress::enabled());
  std::printf("tetraprobe worker %d/%d: traced its share of %d jobs\n", worker.index, worker.count, jobs);
  return 0;
}

}  // namespace tetraprobe::cli
