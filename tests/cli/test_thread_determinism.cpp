// `--threads` never changes the level: the bundled sample baked at 1, 2 and 4 threads gives identical bytes,
// through every threaded stage (placement, path tracing, occlusion, hole filling, refinement, the SH fit, the cell grid).
// Embree's BVH is built on one thread (bake/src/tracer.cpp) so its layout, which decides ties between equally
// near hits, cannot depend on the machine or the option. Small sample counts: about 1.5 s a bake.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(ThreadDeterminism, SampleBakesToIdenticalBytesAtOneTwoAndFourThreads) {
  const fs::path dir = fs::temp_directory_path() / ("tetraprobe_threads_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string scene = std::string(TETRAPROBE_SOURCE_DIR) + "/samples/two_rooms/two_rooms.scene.json";
  const std::string base =
      std::string(TETRAPROBE_CLI) + " bake " + scene +
      " --spacing 1 --samples 16 --noise 0 --fill-holes 1 --probe-budget 32"
      " --refine-points 128 --fit on --fit-points 256 --fit-holdout 128 --fit-samples 32";
  std::string bytes[3];
  const int threads[3] = {1, 2, 4};
  for (int i = 0; i < 3; ++i) {
    const fs::path out = dir / ("t" + std::to_string(threads[i]) + ".tpb");
    const std::string cmd = base + " --threads " + std::to_string(threads[i]) + " -o " + out.string() +
                            " >/dev/null 2>" + (dir / "err.txt").string();
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << cmd << "\n" << slurp(dir / "err.txt");
    bytes[i] = slurp(out);
    ASSERT_GT(bytes[i].size(), 1000u);
  }
  fs::remove_all(dir);
  EXPECT_TRUE(bytes[0] == bytes[1]) << "1 and 2 threads differ";
  EXPECT_TRUE(bytes[0] == bytes[2]) << "1 and 4 threads differ";
}

}  // namespace
