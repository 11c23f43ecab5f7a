// How the path budget (BakeOptions::pathBudget, adaptive sampling's pass 3) is shared among the probes still
// above the target. Build side.
#pragma once

#include <cstdint>
#include <vector>

namespace tetraprobe {

// A probe open to the budget: its batches traced, how many of them its estimate holds (a probe with
// lit-patch sampling restarts its estimate), and its relative standard error now (inf: not yet estimable).
struct BudgetProbe {
  int batches = 0;
  int estimated = 0;
  double error = 0.0;
};

// The batch count each probe stops at in one round of the budget, spending at most `budget` batches in all;
// empty when no probe can be given a batch. A probe at error e over n estimated batches is modelled as
// c / sqrt(n') after n' of them (c = e sqrt(n)); the shares minimise the sum of the modelled errors (the
// bake's mean error) for the batches given: n' proportional to c^(2/3), each capped where the model says the
// probe reaches `target` (n (e / target)^2) and at `ceiling` batches. A probe whose error is not finite is
// weighted as the noisiest and capped only by the ceiling. Deterministic: a pure function of its arguments.
// Post: stops[k] in [open[k].batches, max(open[k].batches, ceiling)], sum of (stops[k] - batches) <= budget.
std::vector<int> budgetShares(const std::vector<BudgetProbe>& open, uint64_t budget, double target,
                              int ceiling);

// The batches a flat per-probe cap would spend on `probes` in all: the sum of flatStops.
uint64_t cappedSpend(const std::vector<BudgetProbe>& probes, double target, int cap);

// Each probe's stop under a flat cap: its batches now where its error is within `target`, else where the model
// above says it reaches the target (n + n_est ((e / target)^2 - 1)), at least its batches now and at most
// max(its batches now, cap); a probe whose error is not finite stops at the cap. Pure function of its arguments.
std::vector<int> flatStops(const std::vector<BudgetProbe>& open, double target, int cap);

}  // namespace tetraprobe
