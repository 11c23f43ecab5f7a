// Build-side utilities: the parallel loop's coverage and error forwarding, atomic file writes.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "tetraprobe/common/parallel.h"
#include "tetraprobe/runtime/file_io.h"

using namespace tetraprobe;

// Every index runs exactly once whatever the thread count and chunk size (the bake writes out[i] by index).
TEST(ParallelFor, EveryIndexRunsExactlyOnce) {
  for (int threads : {1, 2, 3, 8})
    for (size_t chunk : {1, 7, 1000}) {
      std::vector<std::atomic<int>> hits(1237);
      parallelFor(
          hits.size(), threads, [&](size_t i) { hits[i]++; }, chunk);
      for (size_t i = 0; i < hits.size(); ++i)
        ASSERT_EQ(hits[i].load(), 1) << i << " t" << threads << " c" << chunk;
    }
}

// An exception in a worker reaches the caller (a failed probe bake must fail the command, not vanish).
TEST(ParallelFor, ExceptionReachesCaller) {
  EXPECT_THROW(parallelFor(100, 2,
                           [](size_t i) {
                             if (i == 57) throw std::runtime_error("boom");
                           }),
               std::runtime_error);
}

// Zero items is a no-op.
TEST(ParallelFor, EmptyRangeRunsNothing) {
  bool ran = false;
  parallelFor(0, 4, [&](size_t) { ran = true; });
  EXPECT_FALSE(ran);
}

// A write into a missing directory fails with a message and leaves nothing behind; a good write replaces the
// old content whole.
TEST(FileIo, AtomicWriteReplacesWholeOrNothing) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("tp_fileio_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string err;
  EXPECT_FALSE(writeFileAtomic((dir / "no/such/dir/x.bin").string(), "abc", &err));
  EXPECT_NE(err.find("x.bin"), std::string::npos) << err;

  const std::string p = (dir / "x.bin").string();
  ASSERT_TRUE(writeFileAtomic(p, "first version", &err)) << err;
  ASSERT_TRUE(writeFileAtomic(p, "2nd", &err)) << err;
  std::vector<char> bytes;
  ASSERT_TRUE(readFile(p, bytes, &err));
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "2nd");
  int files = 0;
  for (auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1) << "no temporary file may remain";
  fs::remove_all(dir);
}
