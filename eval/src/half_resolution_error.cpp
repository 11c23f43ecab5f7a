// halfResolutionError: the half-resolution lookup against the full-resolution one, per geometry pixel.
#include "tetraprobe/eval/half_resolution_error.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace tetraprobe {

namespace {

double luminance(const float* rgb) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

double quantile(std::vector<double>& sorted, double q) {
  const size_t i = std::min(sorted.size() - 1, size_t(q * double(sorted.size() - 1) + 0.5));
  return sorted[i];
}

}  // namespace

HalfResolutionError halfResolutionError(const Image& full, const Image& half) {
  if (full.width != half.width || full.height != half.height || full.rgba.size() != half.rgba.size() ||
      full.rgba.size() != size_t(full.width) * size_t(full.height) * 4)
    throw std::invalid_argument("halfResolutionError: the two images differ in size");
  HalfResolutionError out;
  double sumY = 0.0;
  size_t count[4] = {0, 0, 0, 0};
  for (size_t i = 0; i < full.rgba.size(); i += 4) {
    if (full.rgba[i + 3] == 0.0f) continue;
    ++out.pixels;
    sumY += luminance(&full.rgba[i]);
    const float code = half.rgba[i + 3];
    ++count[code == 1.0f ? 1 : code == 2.0f ? 2 : code == 3.0f ? 3 : 0];
  }
  if (out.pixels == 0) return out;
  const double n = double(out.pixels);
  out.floor = std::max(0.05 * sumY / n, 0.01);
  out.interpolated = double(count[1]) / n;
  out.copied = double(count[2]) / n;
  out.fullLookup = double(count[3]) / n;
  std::vector<double> d;
  d.reserve(out.pixels);
  for (size_t i = 0; i < full.rgba.size(); i += 4) {
    if (full.rgba[i + 3] == 0.0f) continue;
    const double yf = luminance(&full.rgba[i]), yh = luminance(&half.rgba[i]);
    const double e = std::abs(yh - yf) / std::max(yf, out.floor);
    d.push_back(std::isfinite(e) ? e : 1e30);  // a NaN in the half image counts as the worst pixel
  }
  double sum = 0.0;
  for (double e : d) {
    sum += e;
    out.over5 += e > 0.05 ? 1.0 : 0.0;
    out.over25 += e > 0.25 ? 1.0 : 0.0;
  }
  out.meanRel = sum / n;
  out.over5 /= n;
  out.over25 /= n;
  std::sort(d.begin(), d.end());
  out.p95Rel = quantile(d, 0.95);
  out.p99Rel = quantile(d, 0.99);
  out.maxRel = d.back();
  return out;
}

}  // namespace tetraprobe
