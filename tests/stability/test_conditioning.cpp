// Ill-conditioned tets: slivers up to a barycentric condition number of 1e12, needles, caps, and tets that
// are flat once their positions are rounded to float. Each case names the guard it pins; docs/stability.md
// lists them all. Sliver-rich random levels near and 10 km from the origin are tests/runtime/test_boundary.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "stability_checks.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

using stability::checkLevel;
using stability::Figures;

// Levels with tets of condition above 1e5 bound the jump across faces only by the range: the walk's 1e-6
// tolerance reaches across such thin tets (KNOWN LIMIT in stability_checks.h, with the measured figures).

// Four probes of a unit square with one corner lifted by h (nearly cospherical: their sphere is centred at
// height h/2, so the flat tet they form is Delaunay), one apex above and one below: the sliver sits between
// four tets on each side. Its condition number is about 1/h.
std::vector<glm::dvec3> sliver(double h) {
  return {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, h}, {0.5, 0.5, 1.0}, {0.5, 0.5, -1.0}};
}

// Guard: runtime/src/query.cpp, finish(): the clamp to [0, 1] and renormalization (checked: without it the
// points 1e-7 m off the sliver's faces get negative weights). These axis-aligned slivers' float rows are
// nearly exact (entries powers of ten near 1), so walk()'s switch to exactWeights() is pinned by the cap,
// needle, rotated-sliver and 1 cm to 1 km cases instead (checked: each fails without the switch).
TEST(Stability, SliverWeightsStayInUnitIntervalUpToCondition1e12) {
  double worst = 0.0;
  for (double h : {1e-3, 1e-6, 1e-9, 1e-12}) {
    const Level level = test::makeLevel(sliver(h), glm::dvec3(0.0), 3);
    const std::string name = "sliver h=" + std::to_string(h);
    const Figures fig = checkLevel(level, name.c_str());
    ASSERT_FALSE(HasFatalFailure()) << name;
    EXPECT_GE(fig.worstCondition, 0.1 / h) << name;  // the case is as stiff as it says
    worst = std::max(worst, fig.worstCondition);
  }
  RecordProperty("worst_condition_handled", std::to_string(worst));
  EXPECT_GE(worst, 1e12);
}

// A cap (a vertex 1e-10 m above the inside of its opposite face; the other probe only above it, so it stays
// Delaunay) and a needle (a 1e-6 m triangle joined to probes 1 m away). Guards: walk()'s switch to
// exactWeights() near faces (runtime/src/query.cpp), and buildTetRecords' choice of row offset
// (tetra/src/tetrahedralize.cpp): with the centroid form everywhere the needle's rows err by 0.003 at a
// vertex where rowErrorBound() says 1e-7, and the vertex gets weight 0.003 on a probe it should not see.
TEST(Stability, CapsAndNeedlesGiveExactWeightsAndContinuousIrradiance) {
  const Level cap = test::makeLevel({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, 1e-10}, {0.3, 0.3, 1.0}},
                                    glm::dvec3(0.0), 4);
  const Figures capFig = checkLevel(cap, "cap");
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_GE(capFig.worstCondition, 1e9);
  const double e = 1e-6;
  const Level needle = test::makeLevel(
      {{0, 0, 0}, {e, 0, 0}, {0, e, 0}, {0, 0, 1}, {0, 0, -1}, {0.7, 0.7, 0.3}, {-0.6, 0.5, -0.2}},
      glm::dvec3(0.0), 5);
  const Figures needleFig = checkLevel(needle, "needle");
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_GE(needleFig.worstCondition, 1e5);
}

// A sliver of condition ~1e6 in a random orientation, 10 km from the world origin with the level's local
// frame beside it (as bakes store it): the float rounding of the rotated positions keeps it positive.
// Guard: walk()'s exactWeights() switch, and ProbeQuery::locate() taking world - origin in double.
TEST(Stability, RotatedSliverTenKmOutStaysExact) {
  const glm::dvec3 origin(1e4, -1e4, 1e4);
  const glm::dvec3 ax = glm::normalize(glm::dvec3(0.3, -0.8, 0.5));
  const glm::dvec3 ay = glm::normalize(glm::cross(ax, glm::dvec3(0.1, 0.2, 0.9)));
  const glm::dvec3 az = glm::cross(ax, ay);
  std::vector<glm::dvec3> pts;
  for (const glm::dvec3& p : sliver(1e-6)) pts.push_back(origin + p.x * ax + p.y * ay + p.z * az);
  const Level level = test::makeLevel(pts, origin + glm::dvec3(0.25, 0.5, -0.5), 6);
  const Figures fig = checkLevel(level, "rotated sliver 10 km");
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_GE(fig.worstCondition, 1e5);
}

// Probes 1e-9 m apart 1 m from the level origin collapse to one float position: the tets between them are
// flat in float, where the runtime's exact weights live. Guard: tetra/src/tetrahedralize.cpp,
// checkFloatCollapse() (called by buildTetRecords): an InputError naming the two probes. Without it the
// level is built, and queries in those tets fall back to equal weights (next test). Also exactWeights()
// forming volumes from probe-to-probe edges: with volumes from x - p_i, a point 1e6 m outside the kept
// level is named inside its condition-3.5e9 sliver.
TEST(Stability, TetsFlatInFloatAreNamedAtBuild) {
  const std::vector<glm::dvec3> pts = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0},
                                       {0, 0, 2}, {1, 1, 1}, {1 + 1e-9, 1, 1}};
  const TetMesh mesh = tetrahedralizeDelaunay(pts);  // exact predicates: both probes are vertices
  try {
    buildTetRecords(pts, mesh, glm::dvec3(0.0));
    ADD_FAILURE() << "a tet flat in float was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("probes 4 and 5 at the same float position"), std::string::npos) << what;
  }
  // The same probes with the level origin on them: 1e-9 m is representable there, the level is built and
  // stable (condition ~1e9).
  const Level near = test::makeLevel(pts, glm::dvec3(1, 1, 1), 7);
  const Figures fig = checkLevel(near, "1e-9 apart, origin on them");
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_GE(fig.worstCondition, 1e8);
  // 1 cm spacing 1000 km from a level origin left at the world origin: the float spacing there is 6 cm.
  std::vector<glm::dvec3> far;
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 3; ++x) far.push_back(glm::dvec3(1e6, 0, 0) + 0.01 * glm::dvec3(x, y, z));
  EXPECT_THROW(buildTetRecords(far, tetrahedralizeDelaunay(far), glm::dvec3(0.0)), InputError);
}

// A level from elsewhere may still hold such a tet (query.h documents the answer): two float probes made to
// coincide after the build. Every answer stays finite, normalized and within the probes' range; points
// decided in the flat tets get equal weights. Guard: runtime/src/query.cpp, finish(): a non-finite or
// non-positive weight sum gives 0.25 each instead of NaN.
TEST(Stability, TetFlatInFloatAtRuntimeStillAnswersFinite) {
  const std::vector<glm::dvec3> pts = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {1, 1, 1}, {1.001, 1, 1}};
  Level level = test::makeLevel(pts, glm::dvec3(0.0), 8);
  level.probes[5] = level.probes[4];  // the tets holding both are now flat in float
  const ProbeQuery query(level);
  size_t flatAnswers = 0;
  for (const Tet& t : level.tets) {
    glm::dvec3 c(0.0);
    for (int i = 0; i < 4; ++i) c += 0.25 * glm::dvec3(level.probes[size_t(t.v[i])]);
    for (const glm::dvec3& x : {c, glm::dvec3(1.0005, 1, 1), glm::dvec3(1.0, 1.0, 1.0)}) {
      const Location loc = query.locate(x);
      ASSERT_GE(loc.tet, 0);
      double sum = 0.0;
      for (int i = 0; i < 4; ++i) {
        ASSERT_TRUE(std::isfinite(loc.weights[i]));
        ASSERT_GE(loc.weights[i], 0.0f);
        sum += loc.weights[i];
      }
      EXPECT_NEAR(sum, 1.0, stability::kWeightSum);
      flatAnswers += loc.weights == glm::vec4(0.25f) && !loc.inside;
      const glm::vec3 e = query.irradiance(x, glm::vec3(0, 0, 1));
      const stability::ProbeRange r =
          stability::probeRange(level, level.tets[size_t(loc.tet)], glm::vec3(0, 0, 1));
      for (int ch = 0; ch < 3; ++ch) {
        ASSERT_TRUE(std::isfinite(e[ch]));
        EXPECT_GE(e[ch], r.lo[ch] - stability::kRelRange * r.scale);
        EXPECT_LE(e[ch], r.hi[ch] + stability::kRelRange * r.scale);
      }
    }
  }
  RecordProperty("equal_weight_answers", std::to_string(flatAnswers));
}

}  // namespace
}  // namespace tetraprobe
