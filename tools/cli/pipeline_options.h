// `tetraprobe bake`'s options on the command line and in a level's generator string: the option table (its
// --help shows PipelineOptions{}'s values as the defaults), the parse into PipelineOptions, and the canonical
// list of every option that changes the level, which the generator string records and `bake --options-from`
// and `eval --sweep` read back.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "args.h"
#include "pipeline.h"

namespace tetraprobe::cli {

// The options of `tetraprobe bake`, with help; each default shown is PipelineOptions{}'s (levelOptions).
std::vector<OptionSpec> bakeOptionSpecs();

// The bake's options from parsed `bake` arguments (every option levelOptions lists, and --threads), checked:
// UsageError naming the option for a bad value. Options not given keep PipelineOptions{}'s values, except
// that user probes alone (--probes without --placement, or with --placement none: the file's probes are the
// level's probes) make --fill-holes and --probe-budget 0 unless they are given. --spacing auto stays 0
// (buildLevel resolves it from the scene).
PipelineOptions pipelineOptionsFromArgs(const Args& args);

// Every option that changes the level, as (name, value) pairs in the option table's order, each value as
// `bake` reads it back: numbers in their shortest exact form (parsing the text gives the same double),
// "auto" for an automatic spacing, shell spacing, probe budget or refinement offset. Of --probes and
// --import-sh (only when given) the file's name without its directory, which does not change the level.
// Never the scene, output, report, threads or shard: those do not change the level either.
std::vector<std::pair<std::string, std::string>> levelOptions(const PipelineOptions& options);

// The level's generator string: "tetraprobe 0.1.0 bake" followed by " --name=value" for each of
// levelOptions(options), e.g. "tetraprobe 0.1.0 bake --spacing=1 --placement=voxel ...".
std::string generatorString(const PipelineOptions& options);

// The options a level's generator string records, as `bake` arguments "--name=value": those of
// generatorString, or the "key=value; " items of levels written before it, mapped to their options (what
// those did not record keeps today's default, except a missing path budget: 0, as those levels were baked).
// Empty when the text records no option (a hand-made or imported level).
std::vector<std::string> generatorArguments(const std::string& generator);

// The options a level was baked with: PipelineOptions{} with generatorArguments(generator) applied through
// pipelineOptionsFromArgs. probesCsv and importShCsv hold the recorded file names (no directory).
// `found`, when given, receives the names of the options the text recorded. InputError when a recorded
// value does not parse.
PipelineOptions pipelineOptionsFromGenerator(const std::string& generator,
                                             std::vector<std::string>* found = nullptr);

}  // namespace tetraprobe::cli
