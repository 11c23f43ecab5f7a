// Run-time probe updates: replace the SH of some or all probes of a loaded level in place, without rebuilding
// anything, as an engine does when the time of day changes or a light is switched (the new SH typically come
// from a second bake of the same probes with other lights, exported with `tetraprobe export-sh`, or from the
// engine's own probe update). Permissive: standard library and GLM only.
//
// Nothing a ProbeQuery builds or a level stores besides Level::sh depends on the SH: the tets, outer cells,
// cell grid, start grid and occlusion are functions of the probe positions and the geometry only. So after
// setProbeSh a ProbeQuery built on the same Level answers with the new SH at once, exactly as a query on a
// level freshly built from the same probes with those SH would (tests/render/test_sh_update.cpp checks it
// bit for bit on the CPU and the GPU). The GPU copy is updated with writeLevelSh / cmdUpdateLevelSh
// (vulkan_upload.h).
#pragma once

#include <cstddef>
#include <span>
#include <string>

#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

enum class ShUpdateStatus {
  kOk,
  kOutOfRange,  // first + sh.size() > level.probes.size() (or the sum overflows)
  kNonFinite,   // a coefficient is NaN or infinite
  kTooLarge,    // |coefficient| > kShHalfMaxMagnitude (sh_half.h): beyond what a level file or the GPU holds
  kNotL1,       // the level is L1 (Level::shOrder == 1) and a coefficient 4..8 is not zero
};

struct ShUpdateResult {
  ShUpdateStatus status = ShUpdateStatus::kOk;
  std::string message;  // one line naming the problem (the probe and coefficient); empty when ok
  explicit operator bool() const { return status == ShUpdateStatus::kOk; }
};

// Replaces level.sh[first + i] with quantizeSh(sh[i]) (sh_half.h: the values a level file and the GPU hold, so
// CPU and GPU lookups agree bit for bit) for i in [0, sh.size()): incident radiance, W/(m^2 sr), in the
// convention of sh.h (9 RGB coefficients, index l*(l+1)+m), one record per probe in probe order (the order of
// Level::probes and of `tetraprobe export-sh`). `sh` may be empty (a no-op when first <= probe count).
//
// Validates everything before writing anything: on any failure the level is unchanged and the result names
// the first problem. The checks are the ones validateLevel applies to SH (so the level can still be saved):
// the range lies inside the level, every coefficient is finite and within half precision's range (about
// 2.1e9), and an L1 level receives no L2 coefficients
// (truncate them to zero first, as `bake --sh-order 1` does). Negative radiance is allowed (the L2
// projection rings). Never throws; allocates nothing; O(sh.size()).
//
// Thread safety: writes Level::sh, which ProbeQuery reads without locks. No query on `level` may run during
// the call; queries started after it returns see the new SH (no ProbeQuery needs rebuilding).
ShUpdateResult setProbeSh(Level& level, size_t first, std::span<const ShRgb> sh);

}  // namespace tetraprobe
