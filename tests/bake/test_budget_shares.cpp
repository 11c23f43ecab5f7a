// The path budget's shares (budget_shares.h): within the budget, each probe's need and the ceiling; spending
// what the probes can take; and minimising the modelled mean error, checked against a brute-force search and
// against equal shares (the earlier rule).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "tetraprobe/bake/budget_shares.h"

namespace tetraprobe {
namespace {

constexpr double kTarget = 0.02;
constexpr int kCeiling = 2048;

// The model the shares minimise: error e over n estimated batches falls as e sqrt(n / n').
double modelledSum(const std::vector<BudgetProbe>& open, const std::vector<int>& stops) {
  double sum = 0.0;
  for (size_t k = 0; k < open.size(); ++k) {
    const double n = open[k].estimated, added = stops[k] - open[k].batches;
    sum += std::max(kTarget, open[k].error * std::sqrt(n / (n + added)));  // a probe stops at the target
  }
  return sum;
}

// Batches a probe may take: until the model reaches the target, or the ceiling.
int room(const BudgetProbe& p) {
  const double need = std::ceil(p.estimated * (p.error / kTarget) * (p.error / kTarget) - p.estimated);
  return int(std::min<double>(need, kCeiling - p.batches));
}

std::vector<BudgetProbe> randomProbes(std::mt19937_64& rng, size_t count) {
  std::uniform_int_distribution<int> batches(16, 128);
  std::lognormal_distribution<double> error(std::log(0.06), 0.8);
  std::vector<BudgetProbe> out(count);
  for (BudgetProbe& p : out) {
    p.batches = batches(rng);
    p.estimated = p.batches - int(rng() % 8);  // some restarted their estimate
    p.error = std::max(kTarget * 1.01, error(rng));
  }
  return out;
}

TEST(BudgetShares, NeverExceedTheBudgetAProbesNeedOrTheCeilingAndSpendWhatTheProbesCanTake) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const std::vector<BudgetProbe> open = randomProbes(rng, 1 + rng() % 200);
    const uint64_t budget = rng() % 100000;
    const std::vector<int> stops = budgetShares(open, budget, kTarget, kCeiling);
    uint64_t given = 0, canTake = 0;
    for (size_t k = 0; k < stops.size(); ++k) {
      ASSERT_GE(stops[k], open[k].batches);
      ASSERT_LE(stops[k], kCeiling);
      ASSERT_LE(stops[k] - open[k].batches, room(open[k]));
      given += uint64_t(stops[k] - open[k].batches);
    }
    for (const BudgetProbe& p : open) canTake += uint64_t(room(p));
    ASSERT_LE(given, budget);
    if (stops.empty()) {
      EXPECT_LT(std::min(budget, canTake), open.size() + 1)
          << "nothing given though the probes could take it";
      continue;
    }
    // Rounding down leaves less than one batch a probe of what could be given.
    EXPECT_GE(given + open.size(), std::min(budget, canTake)) << "trial " << trial;
  }
}

TEST(BudgetShares, MinimiseTheModelledMeanErrorAsABruteForceSplitDoes) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    const std::vector<BudgetProbe> open = randomProbes(rng, 2);
    const uint64_t budget = 1 + rng() % 3000;
    const std::vector<int> stops = budgetShares(open, budget, kTarget, kCeiling);
    ASSERT_EQ(stops.size(), 2u);
    double best = std::numeric_limits<double>::infinity();
    for (int a = 0; a <= std::min<int>(int(budget), room(open[0])); ++a) {
      const int b = std::min<int>(int(budget) - a, room(open[1]));
      best = std::min(best, modelledSum(open, {open[0].batches + a, open[1].batches + b}));
    }
    // Within the rounding of one batch a probe (the model's slope at these counts is below 1e-3 a batch).
    EXPECT_LE(modelledSum(open, stops), best + 2e-3) << "trial " << trial;
  }
}

TEST(BudgetShares, GiveALowerModelledMeanErrorThanEqualShares) {
  std::mt19937_64 rng(13);
  for (int trial = 0; trial < 50; ++trial) {
    const std::vector<BudgetProbe> open = randomProbes(rng, 300);
    const uint64_t budget = 20000 + rng() % 40000;
    const std::vector<int> stops = budgetShares(open, budget, kTarget, kCeiling);
    // Equal shares, in rounds as the bake gave them: what a probe does not take goes to the others.
    std::vector<int> equal(open.size());
    for (size_t k = 0; k < open.size(); ++k) equal[k] = open[k].batches;
    uint64_t left = budget;
    for (int round = 0; round < 8 && left > 0; ++round) {
      size_t hungry = 0;
      for (size_t k = 0; k < open.size(); ++k) hungry += equal[k] - open[k].batches < room(open[k]);
      if (hungry == 0 || left / hungry == 0) break;
      const uint64_t share = left / hungry;
      for (size_t k = 0; k < open.size(); ++k) {
        const int take = std::min<int>(int(share), room(open[k]) - (equal[k] - open[k].batches));
        equal[k] += take;
        left -= uint64_t(take);
      }
    }
    EXPECT_LT(modelledSum(open, stops), modelledSum(open, equal)) << "trial " << trial;
  }
}

TEST(BudgetShares, AProbeWithoutAFiniteErrorIsGivenAShareAsTheNoisiest) {
  std::vector<BudgetProbe> open = {{64, 64, 0.05}, {64, 2, std::numeric_limits<double>::infinity()}};
  const std::vector<int> stops = budgetShares(open, 1000, kTarget, kCeiling);
  ASSERT_EQ(stops.size(), 2u);
  EXPECT_GT(stops[1], open[1].batches);
  EXPECT_TRUE(budgetShares(open, 0, kTarget, kCeiling).empty());
  EXPECT_TRUE(budgetShares({}, 1000, kTarget, kCeiling).empty());
}

}  // namespace
}  // namespace tetraprobe
