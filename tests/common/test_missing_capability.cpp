// tests/common/missing_capability.h: a test that lacks a capability skips, and fails instead under
// TETRAPROBE_REQUIRE_ALL (CI), with the same message; only the Vulkan driver/device messages count as missing.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>

#include "missing_capability.h"

namespace {

// Sets (or, with nullopt, unsets) TETRAPROBE_REQUIRE_ALL for one scope, restoring what was there: CI runs
// these tests with it set.
class RequireAllScope {
 public:
  explicit RequireAllScope(const std::optional<std::string>& value) {
    if (const char* v = std::getenv(kName)) saved_ = v;
    if (value)
      setenv(kName, value->c_str(), 1);
    else
      unsetenv(kName);
  }
  ~RequireAllScope() {
    if (saved_)
      setenv(kName, saved_->c_str(), 1);
    else
      unsetenv(kName);
  }

 private:
  static constexpr const char* kName = "TETRAPROBE_REQUIRE_ALL";
  std::optional<std::string> saved_;
};

void missingDevice(bool* after) {
  TETRAPROBE_SKIP_MISSING("no Vulkan device: " << 42);
  *after = true;  // never reached: the macro ends the function
}

// The results `missingDevice` reports, intercepted into `results` (they do not count for this test).
void resultsOfMissingDevice(testing::TestPartResultArray* results, bool* after) {
  testing::ScopedFakeTestPartResultReporter reporter(
      testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, results);
  missingDevice(after);
}

TEST(MissingCapability, RequireAllIsSetByAnyValueButEmptyAndZero) {
  for (const char* on : {"1", "yes", "true", "00"}) {
    RequireAllScope scope{std::string(on)};
    EXPECT_TRUE(tetraprobe::test::requireAll()) << on;
  }
  for (const std::optional<std::string>& off :
       {std::optional<std::string>(), std::optional<std::string>(""), std::optional<std::string>("0")}) {
    RequireAllScope scope(off);
    EXPECT_FALSE(tetraprobe::test::requireAll()) << (off ? "'" + *off + "'" : "unset");
  }
}

// Without the variable: one skip carrying the message, and the code after the macro does not run.
TEST(MissingCapability, SkipsWithItsMessageWhenNotRequired) {
  RequireAllScope scope(std::nullopt);
  bool after = false;
  testing::TestPartResultArray results;
  resultsOfMissingDevice(&results, &after);
  ASSERT_EQ(results.size(), 1);
  EXPECT_TRUE(results.GetTestPartResult(0).skipped());
  EXPECT_STREQ(results.GetTestPartResult(0).message(), "no Vulkan device: 42");
  EXPECT_FALSE(after);
}

// With TETRAPROBE_REQUIRE_ALL=1: one fatal failure carrying the same message, and nothing after it runs.
TEST(MissingCapability, FailsWithItsMessageWhenRequired) {
  RequireAllScope scope(std::string("1"));
  bool after = false;
  testing::TestPartResultArray results;
  resultsOfMissingDevice(&results, &after);
  ASSERT_EQ(results.size(), 1);
  EXPECT_TRUE(results.GetTestPartResult(0).fatally_failed());
  EXPECT_NE(std::string(results.GetTestPartResult(0).message()).find("no Vulkan device: 42"),
            std::string::npos)
      << results.GetTestPartResult(0).message();
  EXPECT_FALSE(after);
}

// The renderer's two "nothing to render on" messages are missing capabilities; other Vulkan errors are not.
TEST(MissingCapability, OnlyNoDriverAndNoDeviceCountAsNoVulkan) {
  using tetraprobe::test::isNoVulkan;
  EXPECT_TRUE(isNoVulkan("no Vulkan driver: install mesa-vulkan-drivers (vkCreateInstance failed)"));
  EXPECT_TRUE(isNoVulkan("tetraprobe render: no Vulkan device: install mesa-vulkan-drivers\n"));
  EXPECT_FALSE(isNoVulkan("no Vulkan memory type with the required properties"));
  EXPECT_FALSE(isNoVulkan("vkCreateComputePipelines failed (-3)"));
  EXPECT_FALSE(isNoVulkan(""));
}

}  // namespace
