// The hostile level set: hand-made bad `.tpb` files (and bad paths), each of which `tetraprobe inspect` must
// answer with exit 2 and one line on stderr naming the file, never a signal or another code. The files are
// made here from a real level baked from a small box (a second), byte by byte: truncations, wrong magic and
// version, bad checksums, and, with the checksums recomputed so the loader's later checks are reached, NaN and
// huge positions, overflowing counts, huge declared sizes, tets sharing a face three ways, flat tets, bad optional sections.
// Layout facts used (offsets, tags): docs/level_format.md. The README's table of bad inputs lists these.
#include <gtest/gtest.h>

#include "level_bytes.h"
#include "tetraprobe/runtime/gpu_sector_pool.h"
#include "tetraprobe/runtime/streaming.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

using namespace tetraprobe::test;

class HostileLevels : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tetraprobe_hostile_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  struct Run {
    int code = -1;
    bool signalled = false;
    std::string err;
  };
  Run run(const std::string& args) {
    const fs::path err = dir_ / "stderr.txt";
    const std::string cmd = std::string(TETRAPROBE_CLI) + " " + args + " >/dev/null 2>" + err.string();
    const int status = std::system(cmd.c_str());
    Run r;
    // system() runs the tool under sh: a signal shows as the shell's exit code 128 + signal.
    r.signalled = WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) >= 128);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(err);
    std::stringstream ss;
    ss << in.rdbuf();
    r.err = ss.str();
    return r;
  }
  fs::path file(const std::string& name, const Bytes& b) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary)
        .write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
    return p;
  }

  fs::path dir_;
};

const char* kBoxObj =
    "mtllib box.mtl\nv 0 0 0\nv 4 0 0\nv 4 0 4\nv 0 0 4\nv 0 3 0\nv 4 3 0\nv 4 3 4\nv 0 3 4\n"
    "v 1.5 2.99 1.5\nv 2.5 2.99 1.5\nv 2.5 2.99 2.5\nv 1.5 2.99 2.5\nusemtl wall\n"
    "f 3 2 1\nf 4 3 1\nf 7 8 5\nf 6 7 5\nf 6 5 1\nf 2 6 1\nf 7 6 2\nf 3 7 2\nf 8 7 3\nf 4 8 3\nf 5 8 4\nf 1 "
    "5 4\n"
    "usemtl light\nf 11 12 9\nf 10 11 9\n";
// StreamingLevel on `path` refuses it: at open, or at the load of some sector (each is tried); `why` is the
// message. The GPU sector pool reads each sector through the same checks (readSector) and must come through every file
// without a fault (the sanitizer build runs this test): it loads what it can.
bool streamingRefuses(const std::string& path, std::string* why) {
  tetraprobe::StreamingLevel st;
  if (const tetraprobe::LevelResult r = st.open(path); !r) {
    *why = r.message;
    return true;
  }
  {
    tetraprobe::StreamingLevel forPool;
    std::vector<tetraprobe::GpuSectorSizes> sizes;
    tetraprobe::GpuSectorPool pool;
    if (forPool.open(path) && tetraprobe::measureSectors(forPool, sizes) &&
        pool.init(forPool, tetraprobe::gpuPoolCapacityFor(sizes, uint32_t(sizes.size()))).empty())
      for (const tetraprobe::SectorKey& key : forPool.sectors()) (void)pool.load(key);
  }
  for (const tetraprobe::SectorKey& key : st.sectors())
    if (const tetraprobe::LevelResult r = st.load(key); !r) {
      *why = r.message;
      return true;
    }
  return false;
}

const char* kBoxMtl = "newmtl wall\nKd 0.7 0.7 0.7\nnewmtl light\nKd 0 0 0\nKe 10 10 10\n";

// Every hostile level: exit 2, one line naming the file, no signal. The good level itself loads (exit 0), so
// each case's failure is its own change. Each case is made from the plain level and from the same level
// with a streaming index (where it applies), and each file also goes through StreamingLevel, which must
// refuse it too, at open or when the sector that reads the damage is loaded.
TEST_F(HostileLevels, InspectExitsTwoWithOneLineForEveryBadFile) {
  std::ofstream(dir_ / "box.obj") << kBoxObj;
  std::ofstream(dir_ / "box.mtl") << kBoxMtl;
  const fs::path good = dir_ / "good.tpb";
  const Run bake =
      run("bake " + (dir_ / "box.obj").string() + " --samples 8 --noise 0 --spacing 1 --fill-holes 0" +
          " --probe-budget 0 --occlusion planes --threads 2 -o " + good.string());
  ASSERT_EQ(bake.code, 0) << bake.err;
  Bytes level;
  {
    std::ifstream in(good, std::ios::binary);
    level.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  ASSERT_GT(level.size(), 200u);
  ASSERT_EQ(run("inspect " + good.string()).code, 0);
  // The same level with a streaming index keeps its tets in fixed records (TETC), which the tet cases forge
  // index by index; the packed ones (TETM, what bake writes) get the cases tetm_*.
  const fs::path streamedPath = dir_ / "streamed.tpb";
  ASSERT_EQ(run("stream " + good.string() + " -o " + streamedPath.string()).code, 0);
  Bytes streamed;
  {
    std::ifstream in(streamedPath, std::ios::binary);
    streamed.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  // Every section of the streamed file is one StreamingLevel reads and checks: no cell grid, no probe kinds.
  EXPECT_NE(findSection(level, "CGR4"), 0u);
  EXPECT_NE(findSection(level, "KIND"), 0u);
  EXPECT_EQ(findSection(streamed, "CGR4"), 0u);
  EXPECT_EQ(findSection(streamed, "KIND"), 0u);

  // Offsets are taken from the copy a case edits (the plain level or the streamed one).
  const auto at = [](const Bytes& b, const char* tag) { return section(b, tag); };
  const size_t tetm = section(level, "TETM");
  const size_t tets = section(streamed, "TETC"), streamedPrbs = section(streamed, "PRBS");
  const uint64_t probeCount = getU64(level, 48), tetCount = getU64(level, 56);
  ASSERT_GE(tetCount, 4u);
  // TETC records: four probe indices of 2 bytes each below 65,536 probes (docs/level_format.md).
  ASSERT_LE(probeCount, 65536u);
  const auto indexAt = [tets](uint64_t t, int i) { return tets + 2 * (4 * size_t(t) + size_t(i)); };
  const auto getIndex = [indexAt](const Bytes& b, uint64_t t, int i) {
    return uint32_t(uint8_t(b[indexAt(t, i)])) | uint32_t(uint8_t(b[indexAt(t, i) + 1])) << 8;
  };
  const auto putIndex = [indexAt](Bytes& b, uint64_t t, int i, uint32_t v) {
    b[indexAt(t, i)] = char(uint8_t(v));
    b[indexAt(t, i) + 1] = char(uint8_t(v >> 8));
  };

  struct Case {
    std::string name;
    std::function<void(Bytes&)> edit;  // applied to a copy of the good level
    bool fixCrc;                       // recompute the checksums after the edit
    bool onStreamed = false;           // edit the streamed copy (fixed tet records) only
    bool plainOnly = false;            // edit the plain copy only (set below)
  };
  const auto truncateTo = [](size_t n) { return [n](Bytes& b) { b.resize(std::min(n, b.size())); }; };
  std::vector<Case> cases = {
      {"empty", truncateTo(0), false},
      {"truncated_magic", truncateTo(5), false},
      {"truncated_header", truncateTo(60), false},
      {"truncated_table", truncateTo(100), false},
      {"truncated_payload", [](Bytes& b) { b.resize(b.size() / 2); }, false},
      {"truncated_last_byte", [](Bytes& b) { b.pop_back(); }, false},
      {"trailing_bytes", [](Bytes& b) { b.insert(b.end(), 16, 0); }, false},
      {"wrong_magic", [](Bytes& b) { b[1] = 'X'; }, false},
      {"text_file",
       [](Bytes& b) {
         b.assign({'h', 'e', 'l', 'l', 'o', '\n'});
       },
       false},
      {"version_2", [](Bytes& b) { putU32(b, 8, 2); }, false},
      {"version_4", [](Bytes& b) { putU32(b, 8, 4); }, true},  // the format before checksummed sectors
      {"version_99", [](Bytes& b) { putU32(b, 8, 99); }, false},
      {"bad_header_crc", [](Bytes& b) { b[40] ^= 1; }, false},
      {"bad_table_crc", [](Bytes& b) { b[90] ^= 1; }, false},
      {"bad_payload_crc", [&](Bytes& b) { b[at(b, "SHRH") + 5] ^= 1; }, false},
      {"header_size", [](Bytes& b) { putU32(b, 12, 96); }, true},
      {"content_flags", [](Bytes& b) { putU32(b, 16, 0xFF); }, true},
      {"sh_order_3", [](Bytes& b) { putU32(b, 20, 3); }, true},
      {"nan_origin", [](Bytes& b) { putU64(b, 24, 0x7FF8000000000000ull); }, true},
      {"probe_count_overflow", [](Bytes& b) { putU64(b, 48, ~0ull); }, true},
      {"tet_count_beyond_int32", [](Bytes& b) { putU64(b, 56, 1ull << 40); }, true},
      {"tet_count_huge_in_range", [](Bytes& b) { putU64(b, 56, 2'000'000'000ull); }, true},
      {"generator_huge", [](Bytes& b) { putU64(b, 64, 1ull << 40); }, true},
      {"section_count_huge", [](Bytes& b) { putU32(b, 72, 100000); }, true},
      {"section_size_huge", [](Bytes& b) { putU64(b, 80 + 24 * 3 + 16, 1ull << 50); }, true},
      {"section_offset_gap", [](Bytes& b) { putU64(b, 80 + 24 + 8, getU64(b, 80 + 24 + 8) + 4); }, true},
      {"unknown_required_section", [](Bytes& b) { putU32(b, 80 + 24 * 3, 0x5A5A5A5A); }, true},
      {"repeated_section", [](Bytes& b) { putU32(b, 80 + 24 * 3, getU32(b, 80 + 24 * 2)); }, true},
      {"nan_position", [&](Bytes& b) { putU32(b, at(b, "PRBS") + 4, 0x7FC00000u); }, true},
      {"inf_position",
       [&](Bytes& b) { putF32(b, at(b, "PRBS") + 8, std::numeric_limits<float>::infinity()); }, true},
      {"huge_position", [&](Bytes& b) { putF32(b, at(b, "PRBS"), 1e30f); }, true},
      {"nan_sh", [&](Bytes& b) { putU32(b, at(b, "SHRH") + 12, 0x7E007E00u); }, true},  // two binary16 NaNs
      {"inf_sh", [&](Bytes& b) { putU32(b, at(b, "SHRH") + 8, 0x00007C00u); }, true},   // +inf, then 0
      // The probe's scale (binary16 27, high half of the record's last uint) must be a power of two.
      {"sh_scale_not_power_of_two",
       [&](Bytes& b) {
         putU32(b, at(b, "SHRH") + 52, (getU32(b, at(b, "SHRH") + 52) & 0xFFFFu) | 0x3C010000u);
       },
       true},
      {"sh_scale_zero",
       [&](Bytes& b) { putU32(b, at(b, "SHRH") + 52, getU32(b, at(b, "SHRH") + 52) & 0xFFFFu); }, true},
      {"sh_scale_negative",
       [&](Bytes& b) {
         putU32(b, at(b, "SHRH") + 52, (getU32(b, at(b, "SHRH") + 52) & 0xFFFFu) | 0xBC000000u);
       },
       true},
      {"vertex_out_of_range", [&](Bytes& b) { putIndex(b, 0, 1, 1u << 15); }, true, true},
      {"vertex_at_probe_count", [&](Bytes& b) { putIndex(b, 1, 2, uint32_t(probeCount)); }, true, true},
      {"vertex_repeated", [&](Bytes& b) { putIndex(b, 0, 1, getIndex(b, 0, 0)); }, true, true},
      // TETM: tet 0 names its four probes by varints (control bytes 0xFF 0xFF; nothing is on the list yet).
      {"tetm_recent_probe_unfilled", [&](Bytes& b) { b[tetm] = 0; }, true},
      {"tetm_vertex_negative", [&](Bytes& b) { b[tetm + 2] = 0x7F; }, true},  // zigzag 127: probe -64
      {"tetm_varint_overlong",
       [&](Bytes& b) {
         for (int i = 0; i < 11; ++i) b[tetm + 2 + size_t(i)] = char(0xFF);
       },
       true},
      // Neighbours are derived from the tets' probes on load: a tet copied over another gives faces of
      // three tets (not a tetrahedralization: a walk could not know which way to go).
      {"tet_copied_over_another",
       [&](Bytes& b) {
         for (int i = 0; i < 4; ++i) putIndex(b, tetCount / 2, i, getIndex(b, 0, i));
       },
       true, true},
      // Tet 0's second probe moved onto its first: flat in float (the build refuses such tets too).
      {"flat_tet",
       [&](Bytes& b) {
         const size_t from = streamedPrbs + 12 * size_t(getIndex(b, 0, 0)),
                      to = streamedPrbs + 12 * size_t(getIndex(b, 0, 1));
         std::memmove(b.data() + to, b.data() + from, 12);
       },
       true, true},
      {"grid_cell_size_zero", [&](Bytes& b) { putF32(b, at(b, "CGR4") + 12, 0.0f); }, true},
      {"grid_slot_count_huge", [&](Bytes& b) { putU64(b, at(b, "CGR4") + 48, 1ull << 33); }, true},
      // CGR4's node stream starts with node 0's varint, zigzag(tet) << 6 | face and child codes: five bytes
      // over it make 2^36 - 1, a tet 2^29 before the first.
      {"grid_node_face_of_missing_tet",
       [&](Bytes& b) {
         const size_t stream = size_t(at(b, "CGR4") + 64 + 16 * getU64(b, at(b, "CGR4") + 48));
         for (int i = 0; i < 5; ++i) b[stream + size_t(i)] = char(i < 4 ? 0xFF : 0x0F);
       },
       true},
      // The same stream opened with a varint that never ends within 64 bits.
      {"grid_node_varint_overlong",
       [&](Bytes& b) {
         const size_t stream = size_t(at(b, "CGR4") + 64 + 16 * getU64(b, at(b, "CGR4") + 48));
         for (int i = 0; i < 11; ++i) b[stream + size_t(i)] = char(0xFF);
       },
       true},
      {"probe_kind_unknown", [&](Bytes& b) { b[at(b, "KIND")] = 200; }, true},
  };

  for (Case& c : cases) {
    // A streamed level stores TETC, not TETM, and neither the cell grid (CGR4: each sector carries its cell's
    // BSP nodes in the index) nor the probe kinds (KIND), which StreamingLevel would never read.
    c.plainOnly =
        c.name.rfind("tetm_", 0) == 0 || c.name.rfind("grid_", 0) == 0 || c.name == "probe_kind_unknown";
  }

  for (const Case& c : cases)
    for (const bool onStreamedCopy : {false, true}) {
      if ((c.onStreamed && !onStreamedCopy) || (c.plainOnly && onStreamedCopy)) continue;
      const std::string name = c.name + (onStreamedCopy && !c.onStreamed ? "_streamed" : "");
      Bytes b = onStreamedCopy ? streamed : level;
      c.edit(b);
      if (c.fixCrc) fixChecksums(b);
      const fs::path p = file(name + ".tpb", b);
      const Run r = run("inspect " + p.string());
      std::string why;
      const bool refused = streamingRefuses(p.string(), &why);
      if (std::getenv("TETRAPROBE_TEST_VERBOSE"))
        std::fprintf(stderr, "%-36s %d %s  streaming: %s\n", name.c_str(), r.code, r.err.c_str(),
                     why.c_str());
      EXPECT_FALSE(r.signalled) << name << ": killed by a signal: " << r.err;
      EXPECT_EQ(r.code, 2) << name << ": " << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << name << ": " << r.err;
      EXPECT_NE(r.err.find(p.filename().string()), std::string::npos) << name << ": " << r.err;
      EXPECT_TRUE(refused) << name << ": StreamingLevel accepts what loadLevel refuses: " << r.err;
    }

  // The level of the previous format version (case version_4): refused naming both versions, on inspect's
  // stderr.
  const Run v4 = run("inspect " + (dir_ / "version_4.tpb").string());
  EXPECT_NE(v4.err.find("format version 4 (this reader understands version 5"), std::string::npos) << v4.err;

  // Paths that are not level files at all: missing, a directory, a device, a file over the size limit
  // (sparse: 5 GiB declared, nothing written).
  const fs::path big = dir_ / "huge.tpb";
  std::ofstream(big).put('x');
  fs::resize_file(big, uint64_t(5) << 30);
  for (const std::string& p :
       {(dir_ / "missing.tpb").string(), dir_.string(), std::string("/dev/zero"), big.string()}) {
    const Run r = run("inspect " + p);
    EXPECT_FALSE(r.signalled) << p << ": " << r.err;
    EXPECT_EQ(r.code, 2) << p << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << p << ": " << r.err;
  }
  const Run r = run("inspect " + big.string());
  EXPECT_NE(r.err.find("more than the limit"), std::string::npos) << r.err;
}

}  // namespace
