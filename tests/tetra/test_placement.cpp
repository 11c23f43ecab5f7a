// Grid probe placement and the probe CSV reader.
#include "tetraprobe/tetra/placement.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "tetraprobe/common/error.h"

namespace tetraprobe {
namespace {

std::string writeTemp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("tetraprobe_test_" + name);
  std::ofstream(path) << text;
  return path.string();
}

// Placement is the input to everything else: its order and margins must be exactly as documented.
TEST(Placement, GridIsCentredAndXFastest) {
  const auto p = placeGridProbes({0, 0, 0}, {10, 5.5, 2}, 2.5);
  ASSERT_EQ(p.size(), size_t(5 * 3 * 1));
  EXPECT_EQ(p[0], glm::dvec3(0.0, 0.25, 1.0));  // y: 5.5 - 2 * 2.5 = 0.5 left over, split evenly; z centred
  EXPECT_EQ(p[1], glm::dvec3(2.5, 0.25, 1.0));  // x varies fastest
  EXPECT_EQ(p[5], glm::dvec3(0.0, 2.75, 1.0));
  EXPECT_EQ(p.back(), glm::dvec3(10.0, 5.25, 1.0));
}

// Bad spacing or a runaway probe count is a user error to report, not an out-of-memory crash.
TEST(Placement, GridRejectsBadSpacingAndTooManyProbes) {
  EXPECT_THROW(placeGridProbes({0, 0, 0}, {1, 1, 1}, 0.0), InputError);
  EXPECT_THROW(placeGridProbes({0, 0, 0}, {1, 1, 1}, -1.0), InputError);
  EXPECT_THROW(placeGridProbes({0, 0, 0}, {1, 1, 1}, std::numeric_limits<double>::quiet_NaN()), InputError);
  EXPECT_THROW(placeGridProbes({0, 0, 0}, {1e6, 1e6, 1e6}, 0.01), InputError);
  EXPECT_THROW(placeGridProbes({0, 0, 0}, {1, -1, 1}, 0.5), InputError);
  EXPECT_EQ(placeGridProbes({0, 0, 0}, {1, 1, 1}, 0.5, 27).size(), 27u);
  EXPECT_THROW(placeGridProbes({0, 0, 0}, {1, 1, 1}, 0.5, 26), InputError);
}

// Hand-edited CSVs carry comments, blank lines, spaces and Windows line ends.
TEST(Placement, CsvReadsValuesAndSkipsComments) {
  const std::string path = writeTemp("ok.csv", "# probes\n1,2,3\n\n  -4.5 , 5e-1,+6\r\n# end\n");
  const auto p = readProbeCsv(path);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[0], glm::dvec3(1, 2, 3));
  EXPECT_EQ(p[1], glm::dvec3(-4.5, 0.5, 6));
  std::remove(path.c_str());
}

// A bad line must be reported with file:line so the user can fix it.
TEST(Placement, CsvRejectsBadLinesWithFileAndLine) {
  const char* bad[] = {"1,2\n", "1,2,3,4\n", "1,x,3\n", "1,nan,3\n", "inf,2,3\n", "1,2,3abc\n", "1,,3\n"};
  for (const char* line : bad) {
    const std::string path = writeTemp("bad.csv", std::string("# header\n0,0,0\n") + line);
    try {
      readProbeCsv(path);
      ADD_FAILURE() << "accepted '" << line << "'";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path + ":3:"), std::string::npos) << e.what();
    }
    std::remove(path.c_str());
  }
  EXPECT_THROW(readProbeCsv("/nonexistent/probes.csv"), InputError);
}

}  // namespace
}  // namespace tetraprobe
