// The probe SH CSV format: write then read gives the same doubles and floats back; headers and comments are
// optional; bad lines are InputErrors naming file and line.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "tetraprobe/bake/sh_csv.h"
#include "tetraprobe/common/error.h"

namespace tetraprobe {
namespace {

ProbeShTable randomTable(int n) {
  std::mt19937 gen(5);
  std::uniform_real_distribution<double> pos(-1e4, 1e4);
  std::uniform_real_distribution<float> coef(-1e3f, 1e3f);
  ProbeShTable t;
  for (int p = 0; p < n; ++p) {
    t.positions.push_back({pos(gen), pos(gen) * 1e-3, 1.0 / (p + 3)});
    ShRgb sh;
    for (int i = 0; i < kShCoeffCount; ++i) sh.c[i] = {coef(gen), coef(gen) * 1e-6f, coef(gen) * 1e20f};
    t.sh.push_back(sh);
  }
  t.sh[0].c[4] =
      glm::vec3(std::numeric_limits<float>::denorm_min(), -0.0f, std::numeric_limits<float>::max());
  return t;
}

// Positions (17 digits) and coefficients (9 digits) survive a round trip exactly, through a file too.
TEST(ShCsv, RoundTripIsExact) {
  const ProbeShTable t = randomTable(50);
  const ProbeShTable back = parseShCsv(formatShCsv(t), "mem");
  ASSERT_EQ(back.positions.size(), t.positions.size());
  for (size_t p = 0; p < t.positions.size(); ++p) {
    EXPECT_EQ(back.positions[p], t.positions[p]) << p;
    EXPECT_EQ(std::memcmp(&back.sh[p], &t.sh[p], sizeof(ShRgb)), 0) << p;
  }
  const auto path = std::filesystem::temp_directory_path() / "tetraprobe_test_sh_csv.csv";
  writeShCsv(path.string(), t);
  const ProbeShTable file = readShCsv(path.string());
  std::filesystem::remove(path);
  ASSERT_EQ(file.sh.size(), t.sh.size());
  EXPECT_EQ(std::memcmp(file.sh.data(), t.sh.data(), t.sh.size() * sizeof(ShRgb)), 0);
}

// Coefficient-major order: field 4 is c0 red, field 5 c0 green, field 7 c1 red; no header needed; comments,
// blank lines, CRLF and spaces are fine.
TEST(ShCsv, ReadsCoefficientMajorWithoutHeader) {
  std::string line = "1, 2 ,3";
  for (int k = 0; k < 27; ++k) line += "," + std::to_string(k + 1);
  const ProbeShTable t = parseShCsv("# engine export\n\n" + line + "\r\n" + line + "\n", "mem");
  ASSERT_EQ(t.sh.size(), 2u);
  EXPECT_EQ(t.positions[0], glm::dvec3(1, 2, 3));
  EXPECT_EQ(t.sh[1].c[0], glm::vec3(1, 2, 3));
  EXPECT_EQ(t.sh[1].c[1], glm::vec3(4, 5, 6));
  EXPECT_EQ(t.sh[1].c[8], glm::vec3(25, 26, 27));
  const ProbeShTable h = parseShCsv(std::string(kShCsvHeader) + "\n" + line, "mem");
  EXPECT_EQ(h.sh.size(), 1u);
}

void expectErrorAt(const std::string& text, const std::string& where) {
  try {
    parseShCsv(text, "probes.csv");
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
  }
}

// Wrong field counts, non-numbers, NaN and Inf are rejected with the file and line; a second non-numeric
// line is not taken for a header.
TEST(ShCsv, BadLinesNameFileAndLine) {
  std::string good = "0,0,0";
  for (int k = 0; k < 27; ++k) good += ",0.5";
  expectErrorAt(good + "\n1,2,3\n", "probes.csv:2:");
  expectErrorAt("# c\n" + good + ",7\n", "probes.csv:2:");
  std::string nan = good;
  nan.replace(nan.size() - 3, 3, "nan");
  expectErrorAt(good + "\n" + nan + "\n", "probes.csv:2:");
  std::string inf = good;
  inf.replace(0, 1, "inf");
  expectErrorAt("\n\n" + good + "\n" + inf, "probes.csv:4:");
  expectErrorAt(std::string(kShCsvHeader) + "\n" + std::string(kShCsvHeader), "probes.csv:2:");
  std::string big = good;
  big.replace(big.size() - 3, 3, "1e39");  // not a finite float
  expectErrorAt(big, "probes.csv:1:");
  EXPECT_THROW(readShCsv("/nonexistent/dir/probes.csv"), InputError);
  EXPECT_TRUE(parseShCsv("", "mem").sh.empty());
}

}  // namespace
}  // namespace tetraprobe
