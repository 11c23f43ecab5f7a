// Deringing of SH L2 probes: a per-probe Hann window over the bands, just strong enough that the
// reconstructed irradiance is non-negative over the whole sphere. The minimum of E over the sphere is found
// by a dense check (a fixed spherical Fibonacci set of kDeringCheckNormals normals) followed by a compass
// search in the tangent plane from the best sample; the strength by bisection on a 1/256 grid.
// References: Sloan 2008 ("Stupid spherical harmonics (SH) tricks", section on windowing / ringing);
// Ramamoorthi & Hanrahan 2001 (the A_l cosine-lobe factors); Marques et al. 2013 (spherical Fibonacci
// point sets); Kolda, Lewis & Torczon 2003 ("Optimization by direct search", compass search).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "sampling.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"

namespace tetraprobe {

namespace {

using sh_const::kA0;
using sh_const::kA1;
using sh_const::kA2;

constexpr int kMaxStep = int(kDeringMaxStrength * kDeringStepsPerUnit);
static_assert(kMaxStep == 512, "strength grid: 0, 1/256, ..., 2");

// The basis at the check normals, computed once.
const std::vector<std::array<double, kShCoeffCount>>& checkBasis() {
  static const std::vector<std::array<double, kShCoeffCount>> basis = [] {
    std::vector<std::array<double, kShCoeffCount>> b(kDeringCheckNormals);
    for (int k = 0; k < kDeringCheckNormals; ++k) {
      const glm::dvec3 n = bake_detail::sphericalFibonacci(k, kDeringCheckNormals);
      b[size_t(k)] = shBasis<double>(n.x, n.y, n.z);
    }
    return b;
  }();
  return basis;
}

// E(n) = e0 + w1 e1(n) + w2 e2(n) per channel: the band contributions of one probe at the check normals.
class ProbeField {
 public:
  explicit ProbeField(const ShRgb& sh) : sh_(sh), bands_(size_t(kDeringCheckNormals)) {
    double maxMean = 0.0;
    for (int c = 0; c < 3; ++c) {
      e0_[c] = kA0 * sh_const::kY00 * double(sh.c[0][c]);
      maxMean = std::max(maxMean, e0_[c]);
    }
    tolerance_ = kDeringTolerance * maxMean;
    const auto& basis = checkBasis();
    for (size_t k = 0; k < basis.size(); ++k) {
      const auto& y = basis[k];
      for (int c = 0; c < 3; ++c) {
        double b1 = 0.0, b2 = 0.0;
        for (int i = 1; i < 4; ++i) b1 += double(sh.c[size_t(i)][c]) * y[size_t(i)];
        for (int i = 4; i < kShCoeffCount; ++i) b2 += double(sh.c[size_t(i)][c]) * y[size_t(i)];
        bands_[k][c] = {kA1 * b1, kA2 * b2};
      }
    }
  }

  double tolerance() const { return tolerance_; }

  // Minimum over the sphere and the channels of E windowed at `strength`.
  double minimum(double strength) const {
    const auto w = deringWindow(strength);
    double best[3];
    size_t arg[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c) best[c] = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < bands_.size(); ++k)
      for (int c = 0; c < 3; ++c) {
        const double e = e0_[c] + w[1] * bands_[k][c][0] + w[2] * bands_[k][c][1];
        if (e < best[c]) {
          best[c] = e;
          arg[c] = k;
        }
      }
    double m = std::numeric_limits<double>::infinity();
    for (int c = 0; c < 3; ++c) {
      const glm::dvec3 start = bake_detail::sphericalFibonacci(int(arg[c]), kDeringCheckNormals);
      m = std::min(m, refine(start, c, w, best[c]));
    }
    return m;
  }

  bool nonNegative(double strength) const { return minimum(strength) >= -tolerance_; }

 private:
  double eval(const glm::dvec3& n, int c, const std::array<double, 3>& w) const {
    const auto y = shBasis<double>(n.x, n.y, n.z);
    double b1 = 0.0, b2 = 0.0;
    for (int i = 1; i < 4; ++i) b1 += double(sh_.c[size_t(i)][c]) * y[size_t(i)];
    for (int i = 4; i < kShCoeffCount; ++i) b2 += double(sh_.c[size_t(i)][c]) * y[size_t(i)];
    return e0_[c] + w[1] * kA1 * b1 + w[2] * kA2 * b2;
  }

  // Compass search on the sphere from `n` (value `value`): four tangent moves of angle h, h halved when none
  // improves, down to 1e-7 rad.
  double refine(glm::dvec3 n, int c, const std::array<double, 3>& w, double value) const {
    value = std::min(value, eval(n, c, w));
    double h = 0.06;  // about the check set's spacing, sqrt(4 pi / 4096) = 0.055 rad
    for (int iter = 0; iter < 400 && h > 1e-7; ++iter) {
      const glm::dvec3 a = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
      const glm::dvec3 t1 = glm::normalize(glm::cross(n, a));
      const glm::dvec3 t2 = glm::cross(n, t1);
      const double th = std::tan(h);
      bool moved = false;
      for (const glm::dvec3& t : {t1, -t1, t2, -t2}) {
        const glm::dvec3 m = glm::normalize(n + th * t);
        const double e = eval(m, c, w);
        if (e < value) {
          value = e;
          n = m;
          moved = true;
          break;
        }
      }
      if (!moved) h *= 0.5;
    }
    return value;
  }

  ShRgb sh_;
  double e0_[3] = {};
  double tolerance_ = 0.0;
  std::vector<std::array<std::array<double, 2>, 3>> bands_;  // [normal][channel] = {band 1, band 2} x A_l
};

double stepStrength(int step) {
  return double(step) / kDeringStepsPerUnit;
}

// Auto strength for one probe with its field already built; also returns the minima before and after.
double autoStrength(const ProbeField& field, bool& fixable, double& before, double& after) {
  fixable = true;
  before = field.minimum(0.0);
  if (before >= -field.tolerance()) {
    after = before;
    return 0.0;
  }
  double hiMin = field.minimum(kDeringMaxStrength);
  if (hiMin < -field.tolerance()) {
    fixable = false;
    after = hiMin;
    return kDeringMaxStrength;
  }
  int lo = 0, hi = kMaxStep;  // invariant: lo fails, hi passes
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    const double m = field.minimum(stepStrength(mid));
    if (m >= -field.tolerance()) {
      hi = mid;
      hiMin = m;
    } else {
      lo = mid;
    }
  }
  after = hiMin;
  return stepStrength(hi);
}

}  // namespace

std::array<double, 3> deringWindow(double strength) {
  const double s = std::clamp(strength, 0.0, kDeringMaxStrength);
  std::array<double, 3> w{1.0, 1.0, 1.0};
  for (int l = 1; l <= 2; ++l)
    w[size_t(l)] = 0.5 * (1.0 + std::cos(std::numbers::pi * std::min(1.0, s * l / 2.0)));
  return w;
}

void applyDeringWindow(ShRgb& sh, double strength) {
  if (!(strength > 0.0)) return;
  const auto w = deringWindow(strength);
  for (int i = 1; i < kShCoeffCount; ++i) sh.c[size_t(i)] *= float(w[i < 4 ? 1 : 2]);
}

float minShIrradiance(const ShRgb& sh, double strength) {
  return float(ProbeField(sh).minimum(strength));
}

double autoDeringStrength(const ShRgb& sh, bool* fixable) {
  bool ok = true;
  double before = 0.0, after = 0.0;
  const double s = autoStrength(ProbeField(sh), ok, before, after);
  if (fixable) *fixable = ok;
  return s;
}

DeringStats deringProbes(std::vector<ShRgb>& sh, const DeringOptions& options) {
  if (options.mode == DeringMode::kFixed &&
      !(std::isfinite(options.strength) && options.strength >= 0.0 && options.strength <= kDeringMaxStrength))
    throw InputError("dering: strength " + std::to_string(options.strength) + " must be in [0, 2]");
  struct PerProbe {
    double strength = 0.0, before = 0.0, after = 0.0;
    bool fixable = true;
  };
  std::vector<PerProbe> per(sh.size());
  parallelFor(
      sh.size(), options.threads,
      [&](size_t i) {
        PerProbe& p = per[i];
        const ProbeField field(sh[i]);
        switch (options.mode) {
          case DeringMode::kNone:
            p.before = p.after = field.minimum(0.0);
            break;
          case DeringMode::kAuto:
            p.strength = autoStrength(field, p.fixable, p.before, p.after);
            break;
          case DeringMode::kFixed:
            p.strength = options.strength;
            p.before = field.minimum(0.0);
            p.after = p.strength > 0.0 ? field.minimum(p.strength) : p.before;
            break;
        }
        if (p.strength > 0.0) {
          applyDeringWindow(sh[i], p.strength);
          p.after = ProbeField(sh[i]).minimum(0.0);  // of the stored (float) coefficients
        }
      },
      16);
  DeringStats stats;
  stats.probes = sh.size();
  double before = std::numeric_limits<double>::infinity(), after = before;
  for (const PerProbe& p : per) {
    if (p.strength > 0.0) ++stats.deringedProbes;
    if (!p.fixable) ++stats.unfixableProbes;
    stats.maxStrength = std::max(stats.maxStrength, p.strength);
    before = std::min(before, p.before);
    after = std::min(after, p.after);
  }
  if (!sh.empty()) {
    stats.minIrradianceBefore = float(before);
    stats.minIrradianceAfter = float(after);
  }
  return stats;
}

}  // namespace tetraprobe
