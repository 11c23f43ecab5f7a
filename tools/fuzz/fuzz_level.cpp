// libFuzzer harness over the level loader (loadLevelFromMemory, runtime/src/level_io.cpp) and the CPU queries
// on whatever it accepts: a level file is untrusted input an engine ships (docs/level_format.md, "Loading
// untrusted files"). Each input is loaded twice: as it is (the checksums reject nearly every mutation), then
// with every checksum recomputed (recomputeLevelChecksums, level_file.h: header, table, payload and a
// streaming index's), so the mutations reach the counts, the section table, the parse and validateLevel. A level that loads is queried inside and outside its hull, one at a time,
// as a batch and as a cached walk (ProbeQuery, which builds the start grid, outer cells and cell grid the file
// may lack). Any crash, sanitizer report, leak or hang is a bug; an error result is the expected outcome.
// Built by `make fuzz` with clang (-fsanitize=fuzzer,address,undefined); seeds: tools/fuzz/make_seeds.sh.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/level_file.h"
#include "tetraprobe/runtime/query.h"

namespace {

void query(const tetraprobe::Level& level) {
  tetraprobe::ProbeQuery q(level, 16.0f, 1);
  glm::dvec3 lo(0.0), hi(0.0);
  if (!level.probes.empty()) {
    lo = hi = glm::dvec3(level.probes[0]);
    for (const glm::vec3& p : level.probes) {
      lo = glm::min(lo, glm::dvec3(p));
      hi = glm::max(hi, glm::dvec3(p));
    }
  }
  lo += level.origin;
  hi += level.origin;
  const glm::dvec3 mid = 0.5 * (lo + hi), ext = hi - lo + glm::dvec3(1.0);
  const glm::vec3 up(0.0f, 1.0f, 0.0f);
  volatile float sink = 0.0f;
  // Single queries: inside (the middle), outside (beyond every face of the bounds), on a probe.
  sink = sink + q.irradiance(mid, up).x;
  sink = sink + q.irradiance(hi + ext, glm::vec3(0.0f)).y;
  sink = sink + q.irradiance(lo - 3.0 * ext, -up).z;
  if (!level.probes.empty()) sink = sink + q.irradiance(glm::dvec3(level.probes.back()) + level.origin, up).x;
  sink = sink + float(q.locate(mid).tet);
  // A batch over a line through the level and beyond it, and the same line as a cached walk.
  constexpr size_t kBatch = 24;
  std::vector<glm::dvec3> points(kBatch);
  std::vector<glm::vec3> normals(kBatch), out(kBatch);
  for (size_t i = 0; i < kBatch; ++i) {
    const double t = double(i) / double(kBatch - 1) * 1.5 - 0.25;
    points[i] = lo + t * (hi - lo) + glm::dvec3(0.0, 0.1 * double(i % 3), 0.0);
    normals[i] = glm::vec3(float(i % 2), float((i + 1) % 2), 0.0f);
  }
  q.irradianceBatch(points.data(), normals.data(), out.data(), kBatch, 1);
  int32_t cache = -1;
  for (size_t i = 0; i < kBatch; ++i) sink = sink + q.irradiance(points[i], normals[i], &cache).x + out[i].x;
  (void)sink;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tetraprobe::Level level;
  if (loadLevelFromMemory(data, size, "fuzz", level)) query(level);
  std::vector<uint8_t> fixed(data, data + size);
  tetraprobe::recomputeLevelChecksums(fixed.data(), fixed.size());
  if (loadLevelFromMemory(fixed.data(), fixed.size(), "fuzz", level)) query(level);
  return 0;
}
