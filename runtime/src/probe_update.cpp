// Run-time probe updates: validate a range of new SH records against the level, then copy them in place
// (probe_update.h). Nothing else in a level or a ProbeQuery depends on the SH, so nothing is rebuilt.
#include "tetraprobe/runtime/probe_update.h"

#include "tetraprobe/runtime/sh_half.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace tetraprobe {
namespace {

ShUpdateResult fail(ShUpdateStatus status, std::string message) {
  return {status, std::move(message)};
}

}  // namespace

ShUpdateResult setProbeSh(Level& level, size_t first, std::span<const ShRgb> sh) {
  const size_t probeCount = level.probes.size();
  if (level.sh.size() != probeCount)
    return fail(ShUpdateStatus::kOutOfRange, "level has " + std::to_string(level.sh.size()) + " SH for " +
                                                 std::to_string(probeCount) + " probes");
  if (first > probeCount || sh.size() > probeCount - first)
    return fail(ShUpdateStatus::kOutOfRange, "SH update of probes [" + std::to_string(first) + ", " +
                                                 std::to_string(first) + " + " + std::to_string(sh.size()) +
                                                 ") outside the level's " + std::to_string(probeCount) +
                                                 " probes");
  for (size_t i = 0; i < sh.size(); ++i) {
    for (int c = 0; c < kShCoeffCount; ++c) {
      const glm::vec3& v = sh[i].c[size_t(c)];
      const auto where = [&] {
        return "SH update: probe " + std::to_string(first + i) + " coefficient " + std::to_string(c);
      };
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        return fail(ShUpdateStatus::kNonFinite, where() + " is not finite");
      if (std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)}) > float(kShHalfMaxMagnitude))
        return fail(ShUpdateStatus::kTooLarge, where() + " is beyond half precision's range (|c| > 2.1e9)");
      if (level.shOrder == 1 && c >= 4 && v != glm::vec3(0.0f))
        return fail(ShUpdateStatus::kNotL1, where() + " is not zero on an L1 level");
    }
  }
  for (size_t i = 0; i < sh.size(); ++i) level.sh[first + i] = quantizeSh(sh[i]);
  return {};
}

}  // namespace tetraprobe
