// libFuzzer harness over the streaming reader (StreamingLevel, runtime/src/streaming.cpp): a streamed level
// is untrusted input an engine ships and opens by path (docs/streaming.md). Each input is written to a file
// of this process's own and opened twice: as it is, then with every checksum recomputed
// (recomputeLevelChecksums, level_file.h: header, table, payload, the index's and each sector's), so the
// mutations reach the table, the index, the sectors' records and validateLevel. Whatever opens has each
// sector loaded (alone, then all together), queried at its centre and unloaded, and goes through the GPU
// sector pool (loads, evictions and its CPU queries). Any crash, sanitizer report, leak or hang is a bug; an
// error result is the expected outcome. Built by `make fuzz` with clang (-fsanitize=fuzzer,address,undefined);
// seeds: tools/fuzz/make_seeds.sh (streamed levels).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/gpu_sector_pool.h"
#include "tetraprobe/runtime/level_file.h"
#include "tetraprobe/runtime/streaming.h"

namespace {

const std::string& file() {
  static const std::string path =
      (std::filesystem::temp_directory_path() / ("tetraprobe_fuzz_streaming." + std::to_string(::getpid())))
          .string();
  return path;
}

void openAndLoad(const std::vector<uint8_t>& bytes) {
  std::ofstream(file(), std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  tetraprobe::StreamingLevel st;
  if (!st.open(file())) return;
  volatile float sink = 0.0f;
  const glm::vec3 up(0.0f, 1.0f, 0.0f);
  size_t tries = 0;
  for (const tetraprobe::SectorKey& key : st.sectors()) {
    if (++tries > 64) break;  // a forged index may name millions of sectors: a few are enough
    if (st.load(key)) {
      sink = sink + st.query(st.coarse().origin, up).x;
      st.unload(key);
    }
  }
  tries = 0;
  for (const tetraprobe::SectorKey& key : st.sectors())
    if (++tries <= 64) (void)st.load(key);
  sink = sink + st.query(st.coarse().origin + glm::dvec3(1.0, 2.0, 3.0), up).y + float(st.bytesInUse());
  // The GPU sector pool over the same file: sized for four sectors, each of the first 64 loaded, evicted
  // every other one, so the slot lists, the links and the cells' hash are exercised on hostile sectors.
  tetraprobe::StreamingLevel forPool;
  if (!forPool.open(file())) return;
  std::vector<tetraprobe::GpuSectorSizes> sizes;
  tetraprobe::GpuSectorPool pool;
  if (!tetraprobe::measureSectors(forPool, sizes) || sizes.size() > 4096 ||
      !pool.init(forPool, tetraprobe::gpuPoolCapacityFor(sizes, 4)).empty())
    return;
  tries = 0;
  for (const tetraprobe::SectorKey& key : forPool.sectors()) {
    if (++tries > 64) break;
    if (pool.load(key) && tries % 2 == 0) pool.evict(key);
  }
  sink = sink + float(pool.takeDirtyRanges().size() + pool.bytesInUse()) +
         pool.irradiance(forPool.coarse().origin + glm::dvec3(1.0, 2.0, 3.0), up).z;
  for (const tetraprobe::SectorKey& key : forPool.sectors()) {  // a CPU query at each loaded cell's corner
    if (!pool.isLoaded(key)) continue;
    const tetraprobe::CellGrid& g = forPool.sectorGrid();
    const glm::dvec3 corner =
        forPool.origin() + glm::dvec3(g.min) + (glm::dvec3(key.x, key.y, key.z) + 0.25) * double(g.cellSize);
    sink = sink + pool.irradiance(corner, up).x;
  }
  (void)sink;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes(data, data + size);
  openAndLoad(bytes);
  tetraprobe::recomputeLevelChecksums(bytes.data(), bytes.size());
  openAndLoad(bytes);
  return 0;
}
