// The streaming index (section STRM, docs/level_format.md) as bytes: its header, its sector records, the
// bytes a sector reads from the index and from the level's own sections, and the checksums over them. One
// reader for StreamingLevel (which reads through a file), loadLevel (which checks an index in memory) and
// saveLevel (which seals the index it writes). Internal to the runtime.
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/level_file.h"

namespace tetraprobe::runtime_detail {

// Reads bytes at file offsets; false when they are not all there.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual bool read(uint64_t at, void* out, size_t n) = 0;
};

class MemorySource final : public ByteSource {
 public:
  MemorySource(const uint8_t* data, uint64_t size) : data_(data), size_(size) {}
  bool read(uint64_t at, void* out, size_t n) override;

 private:
  const uint8_t* data_;
  uint64_t size_;
};

// A file read with seeks, counting the bytes it hands out.
class FileSource final : public ByteSource {
 public:
  bool open(const std::string& path);  // false when it cannot be opened
  uint64_t size() const { return size_; }
  uint64_t bytesRead() const { return bytesRead_; }
  bool read(uint64_t at, void* out, size_t n) override;

 private:
  std::ifstream in_;
  uint64_t size_ = 0, bytesRead_ = 0;
};

inline constexpr uint32_t kStreamVersion = 2;
inline constexpr uint64_t kStreamHeaderBytes = 64, kStreamSectorBytes = 44, kStreamNodeBytes = 24;
inline constexpr uint64_t kStreamCoarseProbeBytes = 12 + 108, kStreamCoarseTetBytes = 32;
inline constexpr uint64_t kStreamIndexCrcAt = 56;   // in the header
inline constexpr uint64_t kStreamSectorCrcAt = 40;  // in a sector record

struct StreamHeader {
  uint32_t sectors = 0;
  glm::vec3 min{0.0f};
  float cellSize = 0.0f;
  uint64_t tetRefs = 0, probeRefs = 0, nodes = 0;
  uint32_t coarseProbes = 0, coarseTets = 0;
  uint32_t crc = 0;  // the index's: header bytes [0, 56), the sector records, the coarse set
  uint64_t sectorsBytes() const { return kStreamSectorBytes * sectors; }
  uint64_t tetRefsAt() const { return kStreamHeaderBytes + sectorsBytes(); }
  uint64_t probeRefsAt() const { return tetRefsAt() + 4 * tetRefs; }
  uint64_t nodesAt() const { return probeRefsAt() + 4 * probeRefs; }
  uint64_t coarseAt() const { return nodesAt() + kStreamNodeBytes * nodes; }
  uint64_t coarseBytes() const {
    return kStreamCoarseProbeBytes * coarseProbes + kStreamCoarseTetBytes * coarseTets;
  }
};
// The header (`h`: the section's first kStreamHeaderBytes) checked against the section's size: "" or what is
// wrong.
std::string parseStreamHeader(const uint8_t* h, uint64_t sectionBytes, StreamHeader& out);
// The index's CRC-32 over the header's bytes [0, 56), the sector records and the coarse set.
uint32_t streamIndexCrc(const uint8_t* header, const uint8_t* sectors, const StreamHeader& h,
                        const uint8_t* coarse);

struct StreamSector {
  int32_t key[3] = {0, 0, 0};
  int32_t root = 0;
  uint32_t tetFirst = 0, tetCount = 0, probeFirst = 0, probeCount = 0, nodeFirst = 0, nodeCount = 0;
  uint32_t crc = 0;  // of the bytes readSectorBytes reads, in its order
};
StreamSector parseStreamSector(const uint8_t* record);
// Its ranges within the header's counts and its key after `previous`'s (null for the first): "" or what is
// wrong.
std::string checkStreamSector(const StreamSector& s, const StreamSector* previous, const StreamHeader& h);

// Where a streamed level keeps what its sectors read: the STRM section, fixed tet records (TETC, or TETS in
// older files), probe positions, SH (SHRH or SHRG) and fixed occlusion records (OCCL, optional).
struct StreamRecords {
  uint64_t strm = 0, strmBytes = 0;
  uint64_t probes = 0, sh = 0, shRecord = 0;
  uint64_t tets = 0, tetRecord = 0, tetIndexBytes = 0;
  uint64_t occl = 0;  // 0: no occlusion section
  uint64_t planes = 0, blocks = 0;
  uint64_t probeCount = 0, tetCount = 0;
};
// From a layout checkLevelSections accepted; reads the OCCL header (24 bytes). "" or what is wrong: no
// STRM, packed tets (TETM) or occlusion (OCC2), which cannot be read record by record, or an OCCL header
// that does not match its section.
std::string locateStreamRecords(const LevelFileLayout& layout, ByteSource& src, StreamRecords& out);

// A sector's bytes as stored, in the order of its CRC: its tet references, its probe references, its nodes
// (from the index), then per tet reference the tet's probe indices (4 x tetIndexBytes), per probe reference
// its position (12) and its SH record, per tet reference its occlusion record (8), then the planes (8 each)
// and shadow-map blocks (64 each) those records name, in tet order.
struct SectorBytes {
  std::vector<uint32_t> tetIds, probeIds;  // decoded references, increasing
  std::vector<uint8_t> nodes, tets, positions, sh, occ, planes, blocks;
  uint32_t crc = 0;  // computed over the bytes read
};
// Reads one sector, checking the references (in range, increasing) and the occlusion records' plane and
// block ranges before they are used to seek, so every read stays inside its section. "" or what is wrong.
std::string readSectorBytes(ByteSource& src, const StreamRecords& rec, const StreamHeader& h,
                            const StreamSector& s, SectorBytes& out);

// A whole file in memory (`layout` parsed from it): checks the index (header, sector records, the index CRC
// and every sector's CRC). "" or what is wrong.
std::string checkStreamIndex(const uint8_t* data, size_t size, const LevelFileLayout& layout);
enum class StreamSeal {
  kAll,         // every sector must read; "" or what is wrong (saveLevel)
  kWhatParses,  // seal what reads, leave the rest (recomputeLevelChecksums)
};
// Computes and writes each sector's CRC and then the index CRC into the STRM section of `data`. The payload
// CRC is the caller's.
std::string sealStreamIndex(uint8_t* data, size_t size, const LevelFileLayout& layout, StreamSeal mode);

}  // namespace tetraprobe::runtime_detail
