// Directional guiding of a probe's sphere paths from a histogram of its own paths. Contract: probe_guide.h.
#include "probe_guide.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace tetraprobe::bake_detail {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kBinSolidAngle = 4.0 * std::numbers::pi / kGuideBins;

int zBin(double z) {
  return std::clamp(int(std::floor((z + 1.0) * 0.5 * kGuideZBins)), 0, kGuideZBins - 1);
}

int phiBin(double x, double y) {
  const double phi = std::atan2(y, x) + std::numbers::pi;  // [0, 2 pi]
  return std::clamp(int(std::floor(phi / kTwoPi * kGuidePhiBins)), 0, kGuidePhiBins - 1);
}

}  // namespace

int guideBin(const glm::vec3& dir) {
  return zBin(double(dir.z)) * kGuidePhiBins + phiBin(double(dir.x), double(dir.y));
}

void GuideHistogram::add(const glm::vec3& dir, double value) {
  if (std::isfinite(value) && value > 0.0) sum[size_t(guideBin(dir))] += value;
}

ProbeGuide::ProbeGuide(const GuideHistogram& histogram) {
  const std::array<double, kGuideBins>& sum = histogram.sum;
  std::array<double, kGuideBins> blurred{};
  double total = 0.0;
  for (int iz = 0; iz < kGuideZBins; ++iz)
    for (int ip = 0; ip < kGuidePhiBins; ++ip) {
      double v = 0.0;
      for (int dz = -1; dz <= 1; ++dz) {
        const int z = iz + dz;
        if (z < 0 || z >= kGuideZBins) continue;
        for (int dp = -1; dp <= 1; ++dp) {
          const int p = (ip + dp + kGuidePhiBins) % kGuidePhiBins;
          v += (dz == 0 && dp == 0 ? 1.0 : 0.125) * sum[size_t(z * kGuidePhiBins + p)];
        }
      }
      blurred[size_t(iz * kGuidePhiBins + ip)] = v;
      total += v;
    }
  if (!(total > 0.0) || !std::isfinite(total)) return;
  double run = 0.0;
  for (int b = 0; b < kGuideBins; ++b) {
    const double p = blurred[size_t(b)] / total;
    run += p;
    cdf_[size_t(b)] = run;
    density_[size_t(b)] = float(p / kBinSolidAngle);
  }
  cdf_[kGuideBins - 1] = 1.0;
  active_ = true;
}

glm::vec3 ProbeGuide::sample(double u1, double u2, double u3) const {
  int b = int(std::upper_bound(cdf_.begin(), cdf_.end(), u1) - cdf_.begin());
  b = std::min(b, kGuideBins - 1);
  while (b > 0 && density_[size_t(b)] == 0.0f) --b;  // u1 at a boundary of an empty bin: its lower neighbour
  while (b < kGuideBins - 1 && density_[size_t(b)] == 0.0f) ++b;
  const int iz = b / kGuidePhiBins, ip = b % kGuidePhiBins;
  const double z = -1.0 + 2.0 * (double(iz) + u2) / kGuideZBins;
  const double phi = (double(ip) + u3) / kGuidePhiBins * kTwoPi - std::numbers::pi;
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return glm::vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
}

float ProbeGuide::pdf(const glm::vec3& dir) const {
  if (!active_) return float(1.0 / (4.0 * std::numbers::pi));
  return density_[size_t(guideBin(dir))];
}

}  // namespace tetraprobe::bake_detail
