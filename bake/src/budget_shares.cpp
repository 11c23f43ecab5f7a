// The path budget's shares (budget_shares.h): the allocation that minimises the sum of errors falling as
// 1 / sqrt(paths). Minimising sum c_k / sqrt(n_k) over sum n_k = N gives c_k / n_k^(3/2) equal for every
// probe, so n_k = lambda c_k^(2/3); lambda is found by bisection on the batches given (monotone in lambda),
// each n_k clamped to [now, where it would reach the target or the ceiling].
#include "tetraprobe/bake/budget_shares.h"

#include <algorithm>
#include <cmath>

namespace tetraprobe {

namespace {

// Batches after its `n` estimated ones at which a probe at error e reaches `target` by the model (e falls as
// 1 / sqrt(n)): n (e / target)^2 - n, unrounded. Needs finite e and target > 0.
double batchesToTarget(double n, double e, double target) {
  return n * (e / target) * (e / target) - n;
}

}  // namespace

std::vector<int> budgetShares(const std::vector<BudgetProbe>& open, uint64_t budget, double target,
                              int ceiling) {
  const size_t m = open.size();
  if (m == 0 || budget == 0) return {};
  std::vector<double> weight(m), lo(m), hi(m);  // in estimated batches: now, and where it would stop
  double maxWeight = 0.0;
  for (size_t k = 0; k < m; ++k) {
    const double n = double(std::max(open[k].estimated, 0)), e = open[k].error;
    const double room = double(std::max(ceiling - open[k].batches, 0));  // batches it may still take
    const double need = std::isfinite(e) && target > 0.0 ? batchesToTarget(n, e, target) : room;
    lo[k] = n;
    hi[k] = n + std::clamp(std::ceil(need), 0.0, room);
    weight[k] = std::isfinite(e) && e >= 0.0 ? std::cbrt(e * e * n) : -1.0;  // (e sqrt(n))^(2/3)
    maxWeight = std::max(maxWeight, weight[k]);
  }
  for (double& w : weight)
    if (w < 0.0) w = maxWeight > 0.0 ? maxWeight : 1.0;
  // Batches given at scale lambda: each probe lambda x weight estimated batches, within [lo, hi].
  auto given = [&](double lambda, std::vector<double>* at) {
    double sum = 0.0;
    for (size_t k = 0; k < m; ++k) {
      const double x = std::floor(std::clamp(lambda * weight[k], lo[k], hi[k]));
      if (at) (*at)[k] = x;
      sum += x - lo[k];
    }
    return sum;
  };
  // An upper scale that gives at least the budget or every probe all it would take.
  double top = 1.0;
  for (;;) {
    if (given(top, nullptr) >= double(budget)) break;
    bool capped = true;
    for (size_t k = 0; k < m && capped; ++k) capped = top * weight[k] >= hi[k];
    if (capped || !(top < 1e300)) break;
    top *= 2.0;
  }
  double bottom = 0.0;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (bottom + top);
    (given(mid, nullptr) <= double(budget) ? bottom : top) = mid;
  }
  std::vector<double> at(m);
  if (given(bottom, &at) < 1.0) return {};
  std::vector<int> stops(m);
  for (size_t k = 0; k < m; ++k)
    stops[k] = std::max(open[k].batches, std::min(ceiling, open[k].batches + int(at[k] - lo[k])));
  return stops;
}

std::vector<int> flatStops(const std::vector<BudgetProbe>& open, double target, int cap) {
  std::vector<int> stops(open.size());
  for (size_t k = 0; k < open.size(); ++k) {
    const BudgetProbe& p = open[k];
    const double n = double(p.batches), est = double(std::max(p.estimated, 0)), e = p.error;
    const double top = std::max(n, double(cap));
    double stop = top;
    if (std::isfinite(e) && e <= target)
      stop = n;
    else if (std::isfinite(e) && target > 0.0)
      stop = std::clamp(n + std::ceil(batchesToTarget(est, e, target)), n, top);
    stops[k] = int(stop);
  }
  return stops;
}

uint64_t cappedSpend(const std::vector<BudgetProbe>& probes, double target, int cap) {
  uint64_t sum = 0;
  for (int stop : flatStops(probes, target, cap)) sum += uint64_t(stop);
  return sum;
}

}  // namespace tetraprobe
