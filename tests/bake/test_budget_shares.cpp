// The path budget's shares (budget_shares.h): within the budget, each probe's need and the ceiling; spending
// what the probes can take; and minimising the modelled mean error, checked against a brute-force search and
// against equal shares (the earlier rule). cappedSpend: what a flat cap spends, and sharing it from half the
// cap against the flat cap.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>
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

// cappedSpend against a flat cap run batch by batch under the model: each probe takes batches until its
// modelled error is within the target or it holds `cap` batches. Equal but for the last batch's rounding.
TEST(CappedSpend, IsWhatAFlatCapSpendsUnderTheModel) {
  std::mt19937_64 rng(17);
  constexpr int kCap = 128;
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<BudgetProbe> probes = randomProbes(rng, 1 + rng() % 100);
    for (size_t k = 0; k < probes.size(); k += 7) probes[k].error = kTarget * 0.5;  // already within
    uint64_t flat = 0;
    for (const BudgetProbe& p : probes) {
      int n = p.batches;
      while (n < kCap && p.error * std::sqrt(double(p.estimated) / (p.estimated + n - p.batches)) > kTarget)
        ++n;
      flat += uint64_t(n);
    }
    const uint64_t spend = cappedSpend(probes, kTarget, kCap);
    EXPECT_GE(spend + probes.size(), flat) << "trial " << trial;
    EXPECT_LE(spend, flat + probes.size()) << "trial " << trial;
  }
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(cappedSpend({{4, 2, inf}}, kTarget, kCap), uint64_t(kCap));  // unknown error: the cap
  EXPECT_EQ(cappedSpend({{300, 300, 0.5}}, kTarget, kCap), 300u);        // past the cap: what it holds
  EXPECT_EQ(cappedSpend({{16, 16, 0.04}}, kTarget, kCap), 64u);          // (0.04 / 0.02)^2 x 16
  EXPECT_EQ(cappedSpend({}, kTarget, kCap), 0u);
}

// What --share-caps does with these two functions: probes stopped at half the cap, then cappedSpend's batches
// shared by budgetShares, against the flat cap on the same probes. The same batches or fewer in all, a
// lower modelled mean error, and no probe past the ceiling. Each probe is modelled by its own constant
// c = e sqrt(n) (the error it would have after n batches).
TEST(CappedSpend, SharedFromHalfTheCapGivesALowerModelledErrorThanTheFlatCapForTheSameBatches) {
  std::mt19937_64 rng(19);
  constexpr int kCap = 128;
  std::lognormal_distribution<double> cDist(std::log(0.02 * std::sqrt(64.0)), 0.9);
  for (int trial = 0; trial < 50; ++trial) {
    const size_t count = 50 + rng() % 250;
    std::vector<double> c(count);
    for (double& x : c) x = cDist(rng);
    auto runTo = [&](size_t k, int cap) {  // batches taken to the target or `cap`, and the error then
      int n = 4;
      while (n < cap && c[k] / std::sqrt(double(n)) > kTarget) ++n;
      return std::make_pair(n, c[k] / std::sqrt(double(n)));
    };
    uint64_t flatBatches = 0;
    double flatSum = 0.0;
    std::vector<BudgetProbe> half(count);
    uint64_t used = 0;
    for (size_t k = 0; k < count; ++k) {
      const auto [n, e] = runTo(k, kCap);
      flatBatches += uint64_t(n);
      flatSum += e;
      const auto [h, eh] = runTo(k, kCap / 2);
      half[k] = {h, h, eh};
      used += uint64_t(h);
    }
    const uint64_t budget = cappedSpend(half, kTarget, kCap);
    ASSERT_LE(budget, flatBatches + count);
    std::vector<BudgetProbe> open;
    std::vector<size_t> which;
    for (size_t k = 0; k < count; ++k)
      if (half[k].error > kTarget) {
        open.push_back(half[k]);
        which.push_back(k);
      }
    const std::vector<int> stops = budgetShares(open, budget - used, kTarget, kCap * 16);
    double sharedSum = 0.0;
    uint64_t sharedBatches = used;
    std::vector<double> e(count);
    for (size_t k = 0; k < count; ++k) e[k] = half[k].error;
    for (size_t m = 0; m < stops.size(); ++m) {
      ASSERT_LE(stops[m], kCap * 16);
      sharedBatches += uint64_t(stops[m] - open[m].batches);
      e[which[m]] = std::max(kTarget, c[which[m]] / std::sqrt(double(stops[m])));
    }
    for (double x : e) sharedSum += x;
    EXPECT_LE(sharedBatches, flatBatches + count) << "trial " << trial;
    EXPECT_LT(sharedSum, flatSum) << "trial " << trial;
  }
}

}  // namespace
}  // namespace tetraprobe
