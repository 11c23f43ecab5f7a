// Probe SH fitted to the surfaces they light (sh_fit.h): the probes are traced at their own positions, but
// what a player sees is their interpolation on the surfaces between them, and where the light changes faster
// than the probes are spaced (a sunlit patch, a lamp, a door gap) the interpolated answer misses. Instead of
// point-sampling the volume, solve for the probe values whose interpolation, exactly as the lookup makes it,
// best matches the traced irradiance at many surface points, pulled toward the traced values by their noise.
// Precomputed-lighting pipelines fit their volumes the same way.
// References: Hestenes & Stiefel 1952 (conjugate gradients); Saad 2003, "Iterative Methods for Sparse Linear
// Systems", 9.2 (Jacobi preconditioning); Ramamoorthi & Hanrahan 2001 (SH irradiance, A_l); Silvennoinen &
// Timonen 2015, "Multi-Scale Global Illumination in Quantum Break" (fitting probe values to surface samples).
#include "tetraprobe/eval/sh_fit.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "tetraprobe/common/parallel.h"
#include "tetraprobe/eval/evaluate.h"
#include "tetraprobe/eval/refine.h"
#include "tetraprobe/runtime/luminance.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/shade.h"

namespace tetraprobe {

namespace {

constexpr double kInv4Pi = 1.0 / (4.0 * std::numbers::pi);

// One fitted point: its tet's probes and the lookup's coefficient of each of their SH terms.
struct Row {
  enum Kind : uint8_t { kFitted, kFallback, kSkipped };
  Kind kind = kSkipped;
  int32_t probe[4] = {0, 0, 0, 0};
  double a[4][kShCoeffCount] = {};     // w_s A_l(k) Y_k(n)
  double w[4] = {0.0, 0.0, 0.0, 0.0};  // w_s: the lookup's weight of each probe
  glm::dvec3 target{0.0}, weight{0.0};
};

bool finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

double rowDot(const Row& r, const std::vector<double>& v) {
  double e = 0.0;
  for (int s = 0; s < 4; ++s) {
    const double* x = &v[size_t(r.probe[s]) * kShCoeffCount];
    for (int k = 0; k < kShCoeffCount; ++k) e += r.a[s][k] * x[k];
  }
  return e;
}

// The same answer, channel c, from per-probe SH.
double rowDot(const Row& r, const std::vector<ShRgb>& sh, int c) {
  double e = 0.0;
  for (int s = 0; s < 4; ++s) {
    const ShRgb& x = sh[size_t(r.probe[s])];
    for (int k = 0; k < kShCoeffCount; ++k) e += r.a[s][k] * double(x.c[size_t(k)][c]);
  }
  return e;
}

void rowScatter(const Row& r, double value, std::vector<double>& y) {
  for (int s = 0; s < 4; ++s) {
    double* x = &y[size_t(r.probe[s]) * kShCoeffCount];
    for (int k = 0; k < kShCoeffCount; ++k) x[k] += r.a[s][k] * value;
  }
}

// The mean irradiance of an SH over normals, per channel: pi Y00 L00.
glm::dvec3 meanIrradiance(const ShRgb& sh) {
  return std::numbers::pi * sh_const::kY00 * glm::dvec3(sh.c[0]);
}

// kRelFloorFraction x the mean target luminance of the points lit at all (evaluate.h's f); 0.01 W/m^2 when
// none is.
double levelFloor(const std::vector<ShFitPoint>& points) {
  double sum = 0.0;
  size_t n = 0;
  for (const ShFitPoint& p : points)
    if (p.target != glm::vec3(0.0f) && finite(glm::dvec3(p.target))) {
      sum += luminance(glm::dvec3(p.target));
      ++n;
    }
  return n > 0 && sum > 0.0 ? kRelFloorFraction * sum / double(n) : 0.01;
}

}  // namespace

std::vector<ShRgb> fitProbeSh(const Level& level, const std::vector<ShFitPoint>& points,
                              const std::vector<float>& probeRelError, const ShFitOptions& options,
                              ShFitStats* statsOut, int threads) {
  const size_t np = level.probes.size();
  if (!(options.lambda >= 0.0)) throw std::invalid_argument("fitProbeSh: lambda must be >= 0");
  if (level.sh.size() != np) throw std::invalid_argument("fitProbeSh: level.sh and level.probes differ");
  if (!probeRelError.empty() && probeRelError.size() != np)
    throw std::invalid_argument("fitProbeSh: probeRelError must hold one entry per probe (or none)");
  ShFitStats stats;
  stats.points = points.size();
  std::vector<ShRgb> out = level.sh;
  if (points.empty() || level.tets.empty() || std::isinf(options.lambda)) {
    stats.otherSkipped = points.size();
    if (statsOut) *statsOut = stats;
    return out;
  }
  const double f = levelFloor(points);
  // An L1 level's coefficients 4..8 are zero and stay so: with no point's row reaching them, their right-hand
  // side is 0 and conjugate gradients never move them off x0.
  const int fittedCoeffs = level.shOrder == 1 ? 4 : kShCoeffCount;

  // The lookup's coefficients at every point (parallel, written by index).
  std::vector<Row> rows(points.size());
  {
    const ProbeQuery query(level, kStoredCellGridOnly);  // a level being built may have no grid yet
    const LevelOcclusion* occlusion = query.occlusion();
    parallelFor(
        points.size(), threads,
        [&](size_t i) {
          const ShFitPoint& p = points[i];
          Row& r = rows[i];
          if (!finite(p.position) || !finite(glm::dvec3(p.target)) || !finite(glm::dvec3(p.stderror)) ||
              !finite(glm::dvec3(p.normal)))
            return;
          const Location loc = query.locate(p.position);
          if (loc.tet < 0) return;
          ShadeRecord record;
          shadeLocated(level, occlusion, loc, p.position, p.normal, &record);
          if (record.fallback > 0.0f) {
            r.kind = Row::kFallback;
            return;
          }
          const Tet& tet = level.tets[size_t(loc.tet)];
          const auto y = shBasis<double>(p.normal.x, p.normal.y, p.normal.z);
          for (int s = 0; s < 4; ++s) {
            r.probe[s] = tet.v[s];
            r.w[s] = double(record.weights[s]);
            for (int k = 0; k < fittedCoeffs; ++k)
              r.a[s][k] = double(record.weights[s]) * shCosineLobe(k) * y[size_t(k)];
          }
          r.target = glm::dvec3(p.target);
          for (int c = 0; c < 3; ++c) {
            const double se = double(p.stderror[c]);
            const double rel = kShFitPointRelFloor * std::max(r.target[c], f);
            r.weight[c] = 1.0 / (se * se + rel * rel);
          }
          r.kind = Row::kFitted;
        },
        64);
  }
  std::vector<uint8_t> touched(np, 0);
  for (const Row& r : rows) {
    if (r.kind == Row::kFitted) {
      ++stats.fitted;
      for (int s = 0; s < 4; ++s) touched[size_t(r.probe[s])] = 1;
    } else if (r.kind == Row::kFallback) {
      ++stats.fallbackPoints;
    } else {
      ++stats.otherSkipped;
    }
  }
  for (uint8_t t : touched) stats.probesTouched += t;
  if (stats.fitted == 0) {
    if (statsOut) *statsOut = stats;
    return out;
  }

  // The prior's diagonal: lambda A_l(k)^2 / (4 pi sd_j^2).
  const size_t n = np * kShCoeffCount;
  std::vector<double> prior(n, 0.0);
  for (size_t j = 0; j < np; ++j) {
    double rel = options.unknownRelError;
    if (!probeRelError.empty() && probeRelError[j] >= 0.0f && std::isfinite(probeRelError[j]))
      rel = double(probeRelError[j]);
    rel = std::max(rel, options.probeRelFloor);
    const double sd = rel * std::max(luminance(glm::max(meanIrradiance(level.sh[j]), glm::dvec3(0.0))), f);
    for (int k = 0; k < kShCoeffCount; ++k) {
      const double a = shCosineLobe(k);
      prior[j * kShCoeffCount + size_t(k)] = options.lambda * a * a * kInv4Pi / (sd * sd);
    }
  }

  // The traced SH per channel as the solver's vectors.
  std::vector<double> x0[3];
  for (int c = 0; c < 3; ++c) {
    x0[c].resize(n);
    for (size_t j = 0; j < np; ++j)
      for (int k = 0; k < kShCoeffCount; ++k)
        x0[c][j * kShCoeffCount + size_t(k)] = double(level.sh[j].c[size_t(k)][c]);
  }

  // Minimises the objective over the rows `use` selects, with the probes `frozen` marks held at x0 (their
  // variables left out: the preconditioner and the right-hand side are 0 there, so conjugate gradients stay in
  // the free subspace). Returns the change per channel c at delta[c * n + ...].
  auto solve = [&](const std::vector<uint8_t>& use, const std::vector<uint8_t>& frozen, int* iterations) {
    std::vector<double> delta(n * 3, 0.0);
    for (int c = 0; c < 3; ++c) {
      // b = A^T W (t - A x0); the Jacobi diagonal of A^T W A + P.
      std::vector<double> b(n, 0.0), diag = prior;
      for (size_t i = 0; i < rows.size(); ++i) {
        const Row& r = rows[i];
        if (!use[i]) continue;
        const double res = r.target[c] - rowDot(r, x0[c]);
        rowScatter(r, r.weight[c] * res, b);
        for (int s = 0; s < 4; ++s)
          for (int k = 0; k < kShCoeffCount; ++k)
            diag[size_t(r.probe[s]) * kShCoeffCount + size_t(k)] += r.weight[c] * r.a[s][k] * r.a[s][k];
      }
      for (size_t j = 0; j < np; ++j)
        if (frozen[j])
          for (int k = 0; k < kShCoeffCount; ++k) {
            b[j * kShCoeffCount + size_t(k)] = 0.0;
            diag[j * kShCoeffCount + size_t(k)] = 0.0;
          }
      auto apply = [&](const std::vector<double>& v, std::vector<double>& y) {
        for (size_t i = 0; i < n; ++i) y[i] = prior[i] * v[i];
        for (size_t i = 0; i < rows.size(); ++i)
          if (use[i]) rowScatter(rows[i], rows[i].weight[c] * rowDot(rows[i], v), y);
      };
      std::vector<double> d(n, 0.0), res = b, z(n), p(n), q(n);
      auto precondition = [&](const std::vector<double>& from, std::vector<double>& to) {
        for (size_t i = 0; i < n; ++i) to[i] = diag[i] > 0.0 ? from[i] / diag[i] : 0.0;
      };
      precondition(res, z);
      p = z;
      double rz = 0.0;
      for (size_t i = 0; i < n; ++i) rz += res[i] * z[i];
      const double rz0 = rz;
      int it = 0;
      while (it < options.maxIterations && rz > 0.0 && rz > options.tolerance * options.tolerance * rz0) {
        apply(p, q);
        double pq = 0.0;
        for (size_t i = 0; i < n; ++i) pq += p[i] * q[i];
        if (!(pq > 0.0)) break;
        const double alpha = rz / pq;
        for (size_t i = 0; i < n; ++i) {
          d[i] += alpha * p[i];
          res[i] -= alpha * q[i];
        }
        precondition(res, z);
        double rzNew = 0.0;
        for (size_t i = 0; i < n; ++i) rzNew += res[i] * z[i];
        const double beta = rzNew / rz;
        rz = rzNew;
        for (size_t i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
        ++it;
      }
      if (iterations) iterations[c] = it;
      std::copy(d.begin(), d.end(), delta.begin() + long(size_t(c) * n));
    }
    return delta;
  };

  // How far a probe may move: per channel, its RMS irradiance change over normals at most maxMove x
  // max(its mean irradiance, f); the whole probe scaled by the smallest channel factor.
  auto applyCapped = [&](const std::vector<double>& delta, size_t* capped) {
    std::vector<ShRgb> result = level.sh;
    for (size_t j = 0; j < np; ++j) {
      const glm::dvec3 e = meanIrradiance(level.sh[j]);
      double scale = 1.0;
      for (int c = 0; c < 3; ++c) {
        double ms = 0.0;
        for (int k = 0; k < kShCoeffCount; ++k) {
          const double a = shCosineLobe(k) * delta[size_t(c) * n + j * kShCoeffCount + size_t(k)];
          ms += a * a * kInv4Pi;
        }
        const double limit = options.maxMove * std::max(e[c], f);
        if (std::sqrt(ms) > limit) scale = std::min(scale, limit / std::sqrt(ms));
      }
      if (scale < 1.0 && capped) ++*capped;
      ShRgb fitted = level.sh[j];
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < kShCoeffCount; ++k)
          fitted.c[size_t(k)][c] = float(double(level.sh[j].c[size_t(k)][c]) +
                                         scale * delta[size_t(c) * n + j * kShCoeffCount + size_t(k)]);
      bool ok = true;
      for (int c = 0; c < 3; ++c) {
        fitted.c[0][c] = std::max(fitted.c[0][c], 0.0f);
        for (int k = 0; k < kShCoeffCount; ++k) ok = ok && std::isfinite(fitted.c[size_t(k)][c]);
      }
      if (ok) result[j] = fitted;
    }
    return result;
  };

  // A row's error under `sh`: the mean over channels of |ln((max(E, 0) + f) / (T + f))|, symmetric in the ratio,
  // so that a point pushed to half its light counts as one pushed to twice it (the gate's gross share counts
  // both).
  auto rowError = [&](const Row& r, const std::vector<ShRgb>& sh) {
    double e = 0.0;
    for (int c = 0; c < 3; ++c)
      e += std::abs(std::log((std::max(rowDot(r, sh, c), 0.0) + f) / (std::max(r.target[c], 0.0) + f)));
    return e / 3.0;
  };

  std::vector<uint8_t> useAll(rows.size(), 0), frozen(np, 0);
  for (size_t i = 0; i < rows.size(); ++i) useAll[i] = rows[i].kind == Row::kFitted ? 1 : 0;
  if (options.crossValidate) {
    // Two-fold cross-validation per probe: fit on every other point, measure the change of the error (rowError)
    // at the points left out, each point's change charged to its tet's probes by their weights. A probe whose
    // fitted value made the points it did not see worse is held at its traced SH in the final fit.
    std::vector<double> charge(np, 0.0);
    for (size_t fold = 0; fold < 2; ++fold) {
      std::vector<uint8_t> use(rows.size(), 0);
      for (size_t i = 0; i < rows.size(); ++i) use[i] = useAll[i] && (i % 2 == fold) ? 1 : 0;
      const std::vector<ShRgb> trial = applyCapped(solve(use, frozen, nullptr), nullptr);
      for (size_t i = 0; i < rows.size(); ++i) {
        if (!useAll[i] || use[i]) continue;
        const double change = rowError(rows[i], trial) - rowError(rows[i], level.sh);
        for (int s = 0; s < 4; ++s) charge[size_t(rows[i].probe[s])] += rows[i].w[s] * change;
      }
    }
    for (size_t j = 0; j < np; ++j) {
      frozen[j] = charge[j] > 0.0 ? 1 : 0;
      stats.heldProbes += frozen[j];
    }
  }
  out = applyCapped(solve(useAll, frozen, stats.iterations), &stats.cappedProbes);
  for (const Row& r : rows)
    if (r.kind == Row::kFitted)
      for (int c = 0; c < 3; ++c) {
        const double res = r.target[c] - rowDot(r, x0[c]);
        stats.objectiveBefore += r.weight[c] * res * res;
      }
  // The data term at the result.
  for (int c = 0; c < 3; ++c)
    for (const Row& r : rows)
      if (r.kind == Row::kFitted) {
        const double res = r.target[c] - rowDot(r, out, c);
        stats.objectiveAfter += r.weight[c] * res * res;
      }
  if (statsOut) *statsOut = stats;
  return out;
}

std::vector<ShFitPoint> shFitPoints(const SceneTracer& tracer, int count, int samples, uint64_t seed,
                                    uint32_t content, int threads, bool progress, const TraceFarm* farm) {
  RefineOptions ro;
  ro.farm = farm;
  ro.points = count;
  ro.samplesPerPoint = samples;
  ro.content = content;
  ro.seed = seed;
  ro.threads = threads;
  ro.progress = progress;
  const std::vector<RefinePoint> drawn = refinePoints(tracer, ro);
  std::vector<ShFitPoint> out(drawn.size());
  for (size_t i = 0; i < drawn.size(); ++i) {
    out[i].position = drawn[i].surface.position;
    out[i].normal = drawn[i].surface.normal;
    out[i].target = drawn[i].reference.irradiance;
    out[i].stderror = drawn[i].reference.stderror;
  }
  return out;
}

ShFitScore shFitScore(const Level& level, const std::vector<ShFitPoint>& points) {
  ShFitScore score;
  if (points.empty() || level.tets.empty()) return score;
  const double f = levelFloor(points);
  constexpr double kGrossFloor = 0.01;                 // W/m^2, as eval
  const ProbeQuery query(level, kStoredCellGridOnly);  // a level being built may have no grid yet
  double sum = 0.0;
  size_t gross = 0;
  for (const ShFitPoint& p : points) {
    if (p.target == glm::vec3(0.0f)) continue;  // no path leaves: no scale to be relative to
    const glm::dvec3 x = glm::dvec3(query.irradiance(p.position, p.normal)), r = glm::dvec3(p.target);
    double e = 0.0;
    for (int c = 0; c < 3; ++c) e += std::abs(x[c] - r[c]) / std::max(r[c], f);
    sum += e / 3.0;
    const double lx = std::max(luminance(x), kGrossFloor), lr = std::max(luminance(r), kGrossFloor);
    gross += (lx > 2.0 * lr || lx < 0.5 * lr) ? 1 : 0;
    ++score.points;
  }
  if (score.points > 0) {
    score.meanRelError = sum / double(score.points);
    score.gross = double(gross) / double(score.points);
  }
  return score;
}

bool shFitKept(const ShFitScore& before, const ShFitScore& after) {
  if (before.points == 0 || after.points == 0) return false;
  return after.meanRelError < before.meanRelError && after.gross <= before.gross;
}

}  // namespace tetraprobe
