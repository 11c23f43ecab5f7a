// Deringing of SH L2 probes (kWindow, kFixed): a per-probe Hann window over the bands, just strong enough that
// the reconstructed irradiance is non-negative over the whole sphere; kAuto's projection is in
// dering_nearest.cpp, and this file's check decides which probes need it and verifies what it gives. The
// minimum of E over the sphere is found by a dense check (a fixed spherical Fibonacci set of
// kDeringCheckNormals normals) followed by a compass search in the tangent plane from the best sample; the
// strength by bisection on a 1/256 grid.
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

// A fixed spherical Fibonacci set of check normals with the basis at each, computed once.
struct CheckSet {
  int count;
  double coverRad;  // every unit vector is within this angle of a member (measured, rounded up)
  std::vector<std::array<double, kShCoeffCount>> basis;
};

CheckSet makeCheckSet(int count, double coverRad) {
  CheckSet set{count, coverRad, std::vector<std::array<double, kShCoeffCount>>(size_t(count))};
  for (int k = 0; k < count; ++k) {
    const glm::dvec3 n = bake_detail::sphericalFibonacci(k, count);
    set.basis[size_t(k)] = shBasis<double>(n.x, n.y, n.z);
  }
  return set;
}

// The dense check (kDeringCheckNormals; covering radius measured 0.0414 rad with 400k random directions)
// and a coarse pre-check of 512 normals (measured 0.1197 rad) that settles most questions on its own: a
// negative sample proves a negative, and a minimum sample above the bound's margin proves none.
const CheckSet& fineSet() {
  static const CheckSet set = makeCheckSet(kDeringCheckNormals, 0.05);
  return set;
}
const CheckSet& coarseSet() {
  static const CheckSet set = makeCheckSet(512, 0.14);
  return set;
}

// Per channel, the largest |band l contribution| to E over the sphere, before windowing:
// A_l |L_l| sqrt((2l + 1) / (4 pi)) (Cauchy-Schwarz with the addition theorem sum_m Y_lm^2 = (2l+1)/(4pi)).
std::array<std::array<double, 3>, 3> bandAmplitudes(const ShRgb& sh) {
  std::array<std::array<double, 3>, 3> amp{};
  for (int c = 0; c < 3; ++c) {
    double n1 = 0.0, n2 = 0.0;
    for (int i = 1; i < 4; ++i) n1 += double(sh.c[size_t(i)][c]) * double(sh.c[size_t(i)][c]);
    for (int i = 4; i < kShCoeffCount; ++i) n2 += double(sh.c[size_t(i)][c]) * double(sh.c[size_t(i)][c]);
    amp[1][c] = kA1 * std::sqrt(n1 * 3.0 / (4.0 * std::numbers::pi));
    amp[2][c] = kA2 * std::sqrt(n2 * 5.0 / (4.0 * std::numbers::pi));
  }
  return amp;
}

// E(n) = e0 + w1 e1(n) + w2 e2(n) per channel: the band contributions of one probe at the check normals
// (the coarse table at once, the fine one when a question needs it).
class ProbeField {
 public:
  explicit ProbeField(const ShRgb& sh) : sh_(sh), amp_(bandAmplitudes(sh)) {
    double maxMean = 0.0;
    for (int c = 0; c < 3; ++c) {
      e0_[c] = kA0 * sh_const::kY00 * double(sh.c[0][c]);
      maxMean = std::max(maxMean, e0_[c]);
    }
    tolerance_ = kDeringTolerance * maxMean;
    fill(coarseSet(), coarse_);
  }

  double tolerance() const { return tolerance_; }

  // Minimum over the sphere and the channels of E windowed at `strength`: the fine check, then refinement of
  // every channel whose best sample could, by the sampling bound, hide a value below the minimum so far.
  double minimum(double strength) const {
    const Dense d = dense(fineSet(), fine(), strength);
    double m = std::numeric_limits<double>::infinity();
    for (int c : d.order) {
      if (d.best[c] - d.margin[c] >= m) continue;  // cannot beat the minimum found so far
      m = std::min(m, refine(d.start(c), c, d.w, d.best[c], d.cover));
    }
    return m;
  }

  // Cheap bounds on minimum(strength) from the coarse check: `hi` is a value E takes (the refined best
  // sample), `lo` the smallest best sample less its margin.
  void bounds(double strength, double& lo, double& hi) const {
    const Dense d = dense(coarseSet(), coarse_, strength);
    const int c = d.order[0];
    hi = refine(d.start(c), c, d.w, d.best[c], d.cover);
    lo = hi;
    for (int k = 0; k < 3; ++k) lo = std::min(lo, d.best[k] - d.margin[k]);
  }

  // minimum(strength) >= -tolerance(), refining only when the checks cannot decide.
  bool nonNegative(double strength) const {
    {
      const Dense d = dense(coarseSet(), coarse_, strength);
      bool clear = true;
      for (int c = 0; c < 3; ++c) {
        if (d.best[c] < -tolerance_) return false;  // a sample is already negative
        clear = clear && d.best[c] - d.margin[c] >= -tolerance_;
      }
      if (clear) return true;  // no room for a negative between samples
    }
    const Dense d = dense(fineSet(), fine(), strength);
    for (int c : d.order) {
      if (d.best[c] < -tolerance_) return false;
      if (d.best[c] - d.margin[c] >= -tolerance_) continue;
      if (refine(d.start(c), c, d.w, d.best[c], d.cover) < -tolerance_) return false;
    }
    return true;
  }

 private:
  using Table = std::vector<std::array<std::array<double, 2>, 3>>;  // [normal][channel] = {band 1, band 2}

  struct Dense {
    std::array<double, 3> w{};
    int count = 0;
    double cover = 0.0;
    double best[3];
    double margin[3];  // how far below best[c] the true minimum can lie
    size_t arg[3] = {0, 0, 0};
    int order[3] = {0, 1, 2};  // channels by ascending best
    glm::dvec3 start(int c) const { return bake_detail::sphericalFibonacci(int(arg[c]), count); }
  };

  void fill(const CheckSet& set, Table& table) const {
    table.resize(set.basis.size());
    for (size_t k = 0; k < set.basis.size(); ++k) {
      const auto& y = set.basis[k];
      for (int c = 0; c < 3; ++c) {
        double b1 = 0.0, b2 = 0.0;
        for (int i = 1; i < 4; ++i) b1 += double(sh_.c[size_t(i)][c]) * y[size_t(i)];
        for (int i = 4; i < kShCoeffCount; ++i) b2 += double(sh_.c[size_t(i)][c]) * y[size_t(i)];
        table[k][c] = {kA1 * b1, kA2 * b2};
      }
    }
  }

  const Table& fine() const {
    if (fine_.empty()) fill(fineSet(), fine_);
    return fine_;
  }

  Dense dense(const CheckSet& set, const Table& table, double strength) const {
    Dense d;
    d.count = set.count;
    d.cover = set.coverRad;
    d.w = deringWindow(strength);
    for (int c = 0; c < 3; ++c) d.best[c] = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < table.size(); ++k)
      for (int c = 0; c < 3; ++c) {
        const double e = e0_[c] + d.w[1] * table[k][c][0] + d.w[2] * table[k][c][1];
        if (e < d.best[c]) {
          d.best[c] = e;
          d.arg[c] = k;
        }
      }
    // On a great circle E is a trigonometric polynomial of degree 2, so |E''| <= sum_l l^2 amp_l (Bernstein)
    // and the true minimum is at most M theta^2 / 2 below its nearest sample (zero slope at a minimum).
    for (int c = 0; c < 3; ++c) {
      const double m = d.w[1] * amp_[1][c] + 4.0 * d.w[2] * amp_[2][c];
      d.margin[c] = 0.5 * m * set.coverRad * set.coverRad;
    }
    std::sort(d.order, d.order + 3,
              [&](int a, int b) { return d.best[a] < d.best[b] || (d.best[a] == d.best[b] && a < b); });
    return d;
  }

  double eval(const glm::dvec3& n, int c, const std::array<double, 3>& w) const {
    const auto y = shBasis<double>(n.x, n.y, n.z);
    double b1 = 0.0, b2 = 0.0;
    for (int i = 1; i < 4; ++i) b1 += double(sh_.c[size_t(i)][c]) * y[size_t(i)];
    for (int i = 4; i < kShCoeffCount; ++i) b2 += double(sh_.c[size_t(i)][c]) * y[size_t(i)];
    return e0_[c] + w[1] * kA1 * b1 + w[2] * kA2 * b2;
  }

  // Compass search on the sphere from `n` (value `value`): four tangent moves of angle h, h halved when none
  // improves (from h = the check set's covering radius), down to 1e-5 rad (E then within ~M 1e-10 of the
  // minimum).
  double refine(glm::dvec3 n, int c, const std::array<double, 3>& w, double value, double h) const {
    value = std::min(value, eval(n, c, w));
    for (int iter = 0; iter < 200 && h > 1e-5; ++iter) {
      const glm::dvec3 a = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
      const glm::dvec3 t1 = glm::normalize(glm::cross(n, a));
      const glm::dvec3 t2 = glm::cross(n, t1);
      bool moved = false;
      for (const glm::dvec3& t : {t1, -t1, t2, -t2}) {
        const glm::dvec3 m = glm::normalize(n + h * t);
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
  std::array<std::array<double, 3>, 3> amp_;
  double e0_[3] = {};
  double tolerance_ = 0.0;
  Table coarse_;
  mutable Table fine_;  // built on first use
};

double stepStrength(int step) {
  return double(step) / kDeringStepsPerUnit;
}

// Auto strength for one probe with its field already built (0 when E >= -tolerance already).
double autoStrength(const ProbeField& field, bool& fixable) {
  fixable = true;
  if (field.nonNegative(0.0)) return 0.0;
  if (!field.nonNegative(kDeringMaxStrength)) {
    fixable = false;
    return kDeringMaxStrength;
  }
  int lo = 0, hi = kMaxStep;  // invariant: lo fails, hi passes
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    if (field.nonNegative(stepStrength(mid)))
      hi = mid;
    else
      lo = mid;
  }
  return stepStrength(hi);
}

// A lower bound of E over the sphere from the band norms alone (no check set needed).
double lowerBound(const ShRgb& sh) {
  const auto amp = bandAmplitudes(sh);
  double lb = std::numeric_limits<double>::infinity();
  for (int c = 0; c < 3; ++c)
    lb = std::min(lb, kA0 * sh_const::kY00 * double(sh.c[0][c]) - amp[1][c] - amp[2][c]);
  return lb;
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
  const double s = autoStrength(ProbeField(sh), ok);
  if (fixable) *fixable = ok;
  return s;
}

DeringStats deringProbes(std::vector<ShRgb>& sh, const DeringOptions& options) {
  if (options.mode == DeringMode::kFixed &&
      !(std::isfinite(options.strength) && options.strength >= 0.0 && options.strength <= kDeringMaxStrength))
    throw InputError("dering: strength " + std::to_string(options.strength) + " must be in [0, 2]");
  struct PerProbe {
    double strength = 0.0;
    bool changed = false;
    bool fixable = true;
    double lo[2] = {0.0, 0.0}, hi[2] = {0.0, 0.0};  // bounds on min E, [0] before and [1] after windowing
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<PerProbe> per(sh.size());
  const std::vector<ShRgb> input = sh;  // for the statistics of windowed probes
  parallelFor(
      sh.size(), options.threads,
      [&](size_t i) {
        PerProbe& p = per[i];
        if (options.mode != DeringMode::kFixed) {
          const double lb = lowerBound(sh[i]);
          if (lb >= 0.0) {  // non-negative without looking closer: strength 0
            p.lo[0] = p.lo[1] = lb;
            p.hi[0] = p.hi[1] = kInf;
            return;
          }
        }
        const ProbeField field(sh[i]);
        field.bounds(0.0, p.lo[0], p.hi[0]);
        if (options.mode == DeringMode::kAuto) {
          if (field.nonNegative(0.0)) {
            p.lo[1] = p.lo[0];
            p.hi[1] = p.hi[0];
            return;
          }
          p.changed = nearestNonNegativeSh(sh[i], &p.fixable);
          // The projection aims a tenth inside the tolerance; should the float coefficients still dip below
          // it, the smallest window takes the rest.
          const ProbeField projected(sh[i]);
          if (p.fixable && !projected.nonNegative(0.0)) p.strength = autoStrength(projected, p.fixable);
          if (p.strength == 0.0) {
            projected.bounds(0.0, p.lo[1], p.hi[1]);  // of the stored (float) coefficients
            return;
          }
        } else if (options.mode == DeringMode::kWindow) {
          p.strength = autoStrength(field, p.fixable);
        } else if (options.mode == DeringMode::kFixed) {
          p.strength = options.strength;
        }
        if (p.strength > 0.0) {
          applyDeringWindow(sh[i], p.strength);
          p.changed = true;
        }
        if (p.changed) {
          ProbeField(sh[i]).bounds(0.0, p.lo[1], p.hi[1]);  // of the stored (float) coefficients
        } else {
          p.lo[1] = p.lo[0];
          p.hi[1] = p.hi[0];
        }
      },
      16);
  // The statistics are exact minima over all probes. Only probes whose lower bound is below the smallest
  // value some probe is known to reach can hold the minimum; only those get the full check. Decided on
  // values alone, so deterministic.
  for (int phase = 0; phase < 2; ++phase) {
    double reached = kInf;
    for (const PerProbe& p : per) reached = std::min(reached, p.hi[phase]);
    parallelFor(
        sh.size(), options.threads,
        [&](size_t i) {
          PerProbe& p = per[i];
          if (!(p.lo[phase] < reached) || p.lo[phase] == p.hi[phase]) return;
          p.lo[phase] = p.hi[phase] = ProbeField(phase == 0 ? input[i] : sh[i]).minimum(0.0);
        },
        16);
  }
  DeringStats stats;
  stats.probes = sh.size();
  double before = kInf, after = kInf;
  for (const PerProbe& p : per) {
    if (p.changed) ++stats.deringedProbes;
    if (!p.fixable) ++stats.unfixableProbes;
    stats.maxStrength = std::max(stats.maxStrength, p.strength);
    before = std::min(before, p.hi[0]);
    after = std::min(after, p.hi[1]);
  }
  if (!sh.empty()) {
    stats.minIrradianceBefore = float(before);
    stats.minIrradianceAfter = float(after);
  }
  return stats;
}

}  // namespace tetraprobe
