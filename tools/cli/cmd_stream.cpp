// `tetraprobe stream LEVEL.tpb -o OUT.tpb`: adds the streaming index (section STRM: per-sector ranges and a
// coarse probe set, tetra/stream_index.h) to a baked level, so an engine can load it sector by sector
// (runtime/streaming.h, docs/streaming.md). The cell grid and the probe kinds are left out (StreamingLevel reads
// neither: each sector carries its cell's BSP in the index; loadLevel's ProbeQuery rebuilds the grid of a
// streamed file); the other sections keep their bytes.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>

#include "args.h"
#include "commands.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/streaming.h"
#include "tetraprobe/tetra/stream_index.h"

namespace tetraprobe::cli {

int cmdStream(int argc, char** argv) {
  Args args(
      "tetraprobe stream LEVEL.tpb -o OUT.tpb [--coarse-spacing 8]",
      "Adds a streaming index to a level: per sector (one 16 m cell of its cell grid) the tets that\n"
      "touch it, their probes and the cell's BSP, and a coarse probe set (one probe per cube of\n"
      "--coarse-spacing metres, tetrahedralized) that answers where no sector is loaded. Written\n"
      "atomically; the cell grid and probe kinds, which a streaming loader never reads, are left out; the\n"
      "level's other sections keep their bytes (docs/streaming.md).",
      {{"--output", "-o", "OUT.tpb", "level file to write (may be LEVEL.tpb itself)", ""},
       {"--coarse-spacing", "", "METRES", "coarse set: one probe per cube of this edge", "8"},
       {"--measure", "", "",
        "then open the written file as an engine would (StreamingLevel) and report the bytes it reads "
        "to open, the memory in use idle and with each sector loaded alone",
        ""}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(1, 1);
  if (!args.has("--output")) throw UsageError("missing -o OUT.tpb");
  StreamIndexOptions options;
  options.coarseSpacing = args.number("--coarse-spacing");
  if (!(options.coarseSpacing > 0.0)) throw UsageError("--coarse-spacing must be positive");
  Level level;
  if (const LevelResult r = loadLevel(args.positional()[0], level); !r) throw InputError(r.message);
  StreamIndexStats stats;
  level.stream = buildStreamIndex(level, options, &stats);
  const double cellSize = double(level.cellGrid.cellSize);
  // Left out: every byte of a streamed file is one StreamingLevel reads and checks, so it refuses what
  // loadLevel refuses (the sectors' BSP nodes are in the index; ProbeQuery rebuilds the grid for loadLevel).
  level.cellGrid = CellGrid{};
  level.probeKinds.clear();
  if (const LevelResult r = saveLevel(args.str("--output"), level); !r) throw std::runtime_error(r.message);
  std::printf(
      "tetraprobe stream: %s -> %s\n  sectors %zu of %g m: %zu tet and %zu probe references (%.2f and %.2f "
      "per tet and probe), %zu BSP nodes; largest sector %zu bytes\n  coarse  %zu probes at %g m, %zu tets\n"
      "  bytes   %zu (index)\n",
      args.positional()[0].c_str(), args.str("--output").c_str(), stats.sectors, cellSize, stats.tetRefs,
      stats.probeRefs, level.tets.empty() ? 0.0 : double(stats.tetRefs) / double(level.tets.size()),
      level.probes.empty() ? 0.0 : double(stats.probeRefs) / double(level.probes.size()), stats.nodes,
      stats.maxSectorBytes, stats.coarseProbes, stats.coarseSpacing, stats.coarseTets, stats.bytes);
  if (args.has("--measure")) {
    StreamingLevel st;
    if (const LevelResult r = st.open(args.str("--output")); !r) throw std::runtime_error(r.message);
    const size_t idle = st.bytesInUse();
    std::printf("  open    read %llu of the file's %llu bytes (header, table, index, coarse set)\n",
                (unsigned long long)st.bytesReadAtOpen(),
                (unsigned long long)std::filesystem::file_size(args.str("--output")));
    size_t lo = SIZE_MAX, hi = 0, sum = 0;
    double seconds = 0.0;
    for (const SectorKey& key : st.sectors()) {
      const auto t0 = std::chrono::steady_clock::now();
      if (const LevelResult r = st.load(key); !r) throw std::runtime_error(r.message);
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const size_t b = st.bytesInUse() - idle;
      lo = std::min(lo, b);
      hi = std::max(hi, b);
      sum += b;
      st.unload(key);
    }
    std::printf("  load    %.2f ms a sector (mean; reads, joins, builds the query)\n",
                st.sectors().empty() ? 0.0 : 1e3 * seconds / double(st.sectors().size()));
    std::printf(
        "  memory  idle %zu bytes (index + coarse set); one sector loaded: +%zu min, +%.0f mean, +%zu max\n",
        idle, st.sectors().empty() ? 0 : lo,
        st.sectors().empty() ? 0.0 : double(sum) / double(st.sectors().size()), hi);
  }
  return 0;
}

}  // namespace tetraprobe::cli
