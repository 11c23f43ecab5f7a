// What a test does when it cannot check what it is for on this machine: it skips, so `make test` passes on
// a machine without a Vulkan driver or device, or without the shared scenes (../shared/scenes beside the
// clone), unless the environment variable TETRAPROBE_REQUIRE_ALL is set to anything but "" or "0". Then the
// same test fails, so a CI run (.ci/run exports TETRAPROBE_REQUIRE_ALL=1) cannot pass green having compared no
// GPU pixel with the CPU (the only guard of the GLSL mirror of the lookup), rendered nothing, or loaded no
// shared scene. Every skip in tests/ goes through it: no Vulkan driver or device (tests/render, eval, visual,
// cli), a queue without timestamps (RenderTimings; lavapipe has them), the shared scenes absent
// (SharedScenes.*, OcclusionScene.VeachAjarFigures), and the visual references being rewritten instead of
// compared (TETRAPROBE_UPDATE_REFERENCES).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <string_view>

namespace tetraprobe::test {

// Whether TETRAPROBE_REQUIRE_ALL is set to a value other than "" and "0" (read at each call).
inline bool requireAll() {
  const char* v = std::getenv("TETRAPROBE_REQUIRE_ALL");
  return v != nullptr && *v != 0 && std::strcmp(v, "0") != 0;
}

// Whether an error message says the machine has no Vulkan driver or no Vulkan device (the two messages of
// render/src/vulkan_context.cpp, also printed by the CLI). Any other Vulkan failure ("no Vulkan memory type
// ...", a shader that fails to build) is a failure of the code under test, never a reason to skip.
inline bool isNoVulkan(std::string_view what) {
  return what.find("no Vulkan driver") != std::string_view::npos ||
         what.find("no Vulkan device") != std::string_view::npos;
}

}  // namespace tetraprobe::test

// Ends the current test (or the void helper it is called in) as skipped with `message` (anything `<<`
// streams, e.g. `path << " not present"`), or as failed, with the same message, when requireAll(). Only for
// what the machine lacks (above); a wrong answer is a failure everywhere.
#define TETRAPROBE_SKIP_MISSING(message)                                                  \
  do {                                                                                    \
    if (::tetraprobe::test::requireAll())                                                 \
      GTEST_FAIL() << "TETRAPROBE_REQUIRE_ALL is set, so this may not skip: " << message; \
    else                                                                                  \
      GTEST_SKIP() << message;                                                            \
  } while (0)
