// The `.tpb` level file: explicit little-endian serialisation, field by field, and a loader that is safe on
// untrusted input (parse -> validate -> hand out, in the manner of cgltf). The byte layout, the field table
// and the version policy are in docs/level_format.md; the header and the section table are parsed and
// checked by level_file.h (shared with StreamingLevel and inspect), the sections' own layouts here.
//
// Integrity: a CRC-32 over the header (checked before any count is trusted) and a CRC-32 over everything
// after it (and, in a streamed level, the index's and each sector's: stream_format.h); then every count is
// checked against the file size before anything is allocated, and every index and number is validated
// (validateLevel) before the level is handed out.
#include <algorithm>
#include <array>
#include <bit>
#include <climits>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include <glm/geometric.hpp>

#include "tetraprobe/runtime/crc32.h"
#include "tetraprobe/runtime/file_io.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/level_file.h"
#include "tetraprobe/runtime/oct_normal.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/runtime/tet_adjacency.h"

#include "bsp_codec.h"
#include "stream_format.h"
#include "tet_codec.h"

namespace tetraprobe {

const char* levelProbeKindName(LevelProbeKind kind) {
  static const char* const kNames[kLevelProbeKindCount] = {
      "user", "surface", "volume", "open", "filler", "shell", "dilated", "hole", "refinement", "grid"};
  return uint8_t(kind) < kLevelProbeKindCount ? kNames[uint8_t(kind)] : "unknown";
}
namespace {

// The header, the table and their checks: level_file.h (one parser for every reader).
constexpr uint32_t kVersion = kLevelFormatVersion;
constexpr uint64_t kHeaderBytes = kLevelHeaderBytes;
constexpr uint64_t kHeaderCrcOffset = kLevelHeaderCrcAt;
constexpr uint64_t kSectionEntryBytes = kLevelSectionEntryBytes;
constexpr uint32_t kSectionRequired = kLevelSectionRequired;
constexpr uint64_t kShBytes = 27 * 4;          // SHRG (read only): 9 coefficients x RGB f32
constexpr uint64_t kShHalfBytes = 28 * 2;      // SHRH: 27 binary16 coefficients + binary16 scale
constexpr uint64_t kTetBytes = 4 * 4 + 4 * 4;  // TETS (read only): v[4] i32, n[4] i32
// TETC: v[4], each levelProbeIndexBytes(P) bytes (2, 3 or 4; neighbours derived on load).
// TETM: two control bytes a tet and a varint for each probe not among the last 15 named (tet_codec.h).
constexpr uint64_t kOuterCellBytes = 3 * 4 + 4 + 3 * 4 + 4 + 9 * 4 + 12;  // v, tet, n, face, normals, pad
constexpr uint64_t kTrailerBytes = 4;                // CRC-32 of bytes [kHeaderBytes, size - 4)
constexpr uint64_t kMaxCount = uint64_t(INT32_MAX);  // probe and tet indices are int32
constexpr uint64_t kMaxGeneratorBytes = 1u << 20;
// Probe positions are local (relative to the level's double origin): beyond 2^24 m (16,777 km, more than the
// Earth's diameter) a float holds a position to no better than 2 m, and the cell-grid keys built from them
// on load could leave the int32 range for small cells. The bake centres the origin on the probes.
constexpr float kMaxLocalCoordinate = 16777216.0f;
static_assert(kTetBytes == sizeof(Tet), "the old tet record is the GPU's 32-byte std430 Tet");
static_assert(kShBytes == sizeof(ShRgb), "the old SH record is the 108-byte ShRgb");
static_assert(kShHalfBytes == sizeof(ShHalf), "the file's SH record is the 56-byte ShHalf");
static_assert(kOuterCellBytes == sizeof(OuterCell),
              "the old outer cell record (OUTC, read only) is the 80-byte OuterCell");

// Section tags as saveLevel writes them (level_file.h).
constexpr uint32_t kTagProbes = levelTag("PRBS"), kTagShHalf = levelTag("SHRH"),
                   kTagTetsCompact = levelTag("TETC"), kTagTetsPacked = levelTag("TETM"),
                   kTagGenerator = levelTag("GENR"), kTagCellGrid = levelTag("CGR2"),
                   kTagCellGridPacked = levelTag("CGR4"), kTagOcclusion = levelTag("OCCL"),
                   kTagOcclusionPacked = levelTag("OCC2"), kTagProbeKinds = levelTag("KIND"),
                   kTagStream = levelTag("STRM");
constexpr uint64_t kOcclusionHeaderBytes = 24;  // tet, plane and shadow-map block counts (u64 each)
constexpr uint64_t kTetOcclusionBytes = 8, kOcclusionPlaneBytes = 8;  // plane: 4 x snorm16
// OCC2: the counts and the cell-mask byte count (u64 each), then a code byte per tet (kind | plane count << 2)
// and the cell masks of the plane tets, 2^count x 4 bits each (1, 2 or 4 bytes); offsets are implicit (each
// tet's planes and block follow the previous tet's).
constexpr uint64_t kOcclusionPackedHeaderBytes = 32;
// The cell-mask bytes of a plane tet with 1..3 planes: 2^count cells x 4 bits.
constexpr uint32_t occlusionCellBytes(uint32_t planeCount) {
  return 1u << (planeCount - 1);
}

// True when every record's offset is where the packed form (OCC2) puts it: its planes and shadow-map block
// right after the previous record's, in tet order (how buildOcclusion lays them out).
bool occlusionPackable(const LevelOcclusion& occ) {
  uint64_t planes = 0, blocks = 0;
  for (const TetOcclusion& rec : occ.tets) {
    if (rec.kind() == kOcclusionPlanes) {
      if (rec.offset() != planes) return false;
      planes += rec.planeCount();
    } else if (rec.kind() == kOcclusionShadowMaps) {
      if (rec.offset() != blocks) return false;
      ++blocks;
    }
  }
  return true;
}
// CGR2: min, cellSize, maxProbe, maxDepth, meanDepth, leaves, unproven leaves, slot and node counts. (The
// retired CGRD section, leaves of several tets, is an unknown optional tag now: skipped, the grid rebuilt.)
constexpr uint64_t kCellGridHeaderBytes = 64;
// CGR4: the same header and slots, then the nodes as a varint stream naming the tet face each plane was cut
// from and what its children are (bsp_codec.h; about 3 bytes a node). The retired CGR3 (12-byte nodes) is an
// unknown optional tag now: skipped, the grid rebuilt.
constexpr uint64_t kSlotBytes = 16, kNodeBytes = 24;
constexpr uint64_t kMaxFaceNodeTets = uint64_t(1) << 30;  // tet << 2 | face fits a u32

// For every node of `g`, the face (tet << 2 | face) whose cellGridFacePlane is the node's plane bit for bit;
// false when some node has none (a grid not built by buildCellGrid: written as CGR2, as is one whose nodes
// are not in preorder). Coplanar faces give the
// same floats; the smallest reference is taken, so the output is a pure function of the level.
bool nodeFaces(const Level& level, std::vector<uint32_t>& out) {
  const CellGrid& g = level.cellGrid;
  if (level.tets.size() >= kMaxFaceNodeTets) return false;
  using Key = std::array<uint32_t, 4>;
  std::vector<std::pair<Key, uint32_t>> faces;
  faces.reserve(4 * level.tets.size());
  for (size_t t = 0; t < level.tets.size(); ++t) {
    glm::vec3 corners[4];
    for (int i = 0; i < 4; ++i) corners[i] = level.probes[size_t(level.tets[t].v[i])];
    for (int f = 0; f < 4; ++f) {
      float plane[4];
      if (!cellGridFacePlane(corners, f, plane)) continue;
      Key k;
      for (int a = 0; a < 4; ++a) k[size_t(a)] = std::bit_cast<uint32_t>(plane[a]);
      faces.emplace_back(k, uint32_t(t) << 2 | uint32_t(f));
    }
  }
  std::sort(faces.begin(), faces.end());
  out.resize(g.nodes.size());
  for (size_t n = 0; n < g.nodes.size(); ++n) {
    Key k;
    for (int a = 0; a < 4; ++a) k[size_t(a)] = std::bit_cast<uint32_t>(g.nodes[n].plane[a]);
    const auto it = std::lower_bound(faces.begin(), faces.end(), std::make_pair(k, uint32_t(0)));
    if (it == faces.end() || it->first != k) return false;
    out[n] = it->second;
  }
  return true;
}

// --- writing ---------------------------------------------------------------------------------------------
class Writer {
 public:
  void bytes(const void* p, size_t n) { out_.append(static_cast<const char*>(p), n); }
  void u32(uint32_t v) {
    for (int i = 0; i < 4; ++i) out_.push_back(char(uint8_t(v >> (8 * i))));
  }
  void u64(uint64_t v) {
    for (int i = 0; i < 8; ++i) out_.push_back(char(uint8_t(v >> (8 * i))));
  }
  void i32(int32_t v) { u32(uint32_t(v)); }
  void uN(uint32_t v, uint32_t n) {  // the low n bytes of v
    for (uint32_t i = 0; i < n; ++i) out_.push_back(char(uint8_t(v >> (8 * i))));
  }
  void i16(int16_t v) {
    out_.push_back(char(uint8_t(uint16_t(v))));
    out_.push_back(char(uint8_t(uint16_t(v) >> 8)));
  }
  void f32(float v) { u32(std::bit_cast<uint32_t>(v)); }
  void f64(double v) { u64(std::bit_cast<uint64_t>(v)); }
  void patchU32(size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) out_[at + size_t(i)] = char(uint8_t(v >> (8 * i)));
  }
  uint32_t crcOf(size_t from, size_t to) const {
    return crc32(reinterpret_cast<const uint8_t*>(out_.data()) + from, to - from);
  }
  std::string& str() { return out_; }

 private:
  std::string out_;
};

// --- reading (bounds are checked by the caller against the file size before any read)
// -----------------------
class Reader {
 public:
  explicit Reader(const uint8_t* p) : p_(p) {}
  uint32_t u32() {
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= uint32_t(p_[i]) << (8 * i);
    p_ += 4;
    return v;
  }
  uint64_t u64() {
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= uint64_t(p_[i]) << (8 * i);
    p_ += 8;
    return v;
  }
  int32_t i32() { return int32_t(u32()); }
  uint32_t uN(uint32_t n) {
    uint32_t v = 0;
    for (uint32_t i = 0; i < n; ++i) v |= uint32_t(p_[i]) << (8 * i);
    p_ += n;
    return v;
  }
  int16_t i16() {
    const auto v = uint16_t(p_[0] | p_[1] << 8);
    p_ += 2;
    return int16_t(v);
  }
  float f32() { return std::bit_cast<float>(u32()); }
  double f64() { return std::bit_cast<double>(u64()); }
  const uint8_t* skip(size_t n) {
    const uint8_t* at = p_;
    p_ += n;
    return at;
  }

 private:
  const uint8_t* p_;
};

LevelResult fail(LevelStatus status, std::string message) {
  return {status, std::move(message)};
}

bool finite3(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// What is wrong with probe i's local position (non-finite, or beyond kMaxLocalCoordinate), or "".
std::string positionError(const glm::vec3& p, size_t i) {
  if (!finite3(p)) return "probe " + std::to_string(i) + ": non-finite position";
  if (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) > kMaxLocalCoordinate)
    return "probe " + std::to_string(i) + ": position beyond " +
           std::to_string(int64_t(kMaxLocalCoordinate)) + " m of the level origin";
  return {};
}

// validateLevel; `linked`: the tets' neighbours were derived by linkTetNeighbours from vertices already
// checked (in range, pairwise distinct), so they are consistent by construction (the other tet naming the
// same three probes names this one back across that face) and their checks are skipped. Everything else,
// the flat-tet check included, runs either way.
LevelResult validateLevelChecks(const Level& level, bool linked) {
  const auto corrupt = [](std::string m) { return fail(LevelStatus::kCorrupt, std::move(m)); };
  if ((level.content & ~uint32_t(kContentAll)) != 0)
    return corrupt("unknown content flags " + std::to_string(level.content) +
                   " (known: " + std::to_string(uint32_t(kContentAll)) + ")");
  if (level.shOrder != 1 && level.shOrder != 2)
    return corrupt("SH order " + std::to_string(level.shOrder) + " (expected 1 or 2)");
  if (!std::isfinite(level.origin.x) || !std::isfinite(level.origin.y) || !std::isfinite(level.origin.z))
    return corrupt("non-finite origin");
  if (level.probes.size() > kMaxCount || level.tets.size() > kMaxCount)
    return corrupt(std::to_string(level.probes.size()) + " probes / " + std::to_string(level.tets.size()) +
                   " tets exceed the int32 index range");
  if (level.sh.size() != level.probes.size())
    return corrupt(std::to_string(level.probes.size()) + " probes but " + std::to_string(level.sh.size()) +
                   " SH records");
  if (level.generator.size() > kMaxGeneratorBytes)
    return corrupt("generator string of " + std::to_string(level.generator.size()) + " bytes exceeds " +
                   std::to_string(kMaxGeneratorBytes));
  const int64_t probeCount = int64_t(level.probes.size()), tetCount = int64_t(level.tets.size());
  for (int64_t p = 0; p < probeCount; ++p) {
    const glm::vec3& pos = level.probes[size_t(p)];
    if (std::string e = positionError(pos, size_t(p)); !e.empty()) return corrupt(std::move(e));
    const ShRgb& sh = level.sh[size_t(p)];
    for (int i = 0; i < kShCoeffCount; ++i) {
      if (!finite3(sh.c[size_t(i)]))
        return corrupt("probe " + std::to_string(p) + ": non-finite SH coefficient " + std::to_string(i));
      if (level.shOrder == 1 && i >= 4 && sh.c[size_t(i)] != glm::vec3(0.0f))
        return corrupt("probe " + std::to_string(p) + ": L1 level with non-zero L2 coefficient " +
                       std::to_string(i));
    }
  }
  for (int64_t t = 0; t < tetCount && !linked; ++t) {
    const Tet& tet = level.tets[size_t(t)];
    const auto where = [t] { return "tet " + std::to_string(t) + ": "; };  // built only for a message
    for (int i = 0; i < 4; ++i) {
      if (tet.v[i] < 0 || tet.v[i] >= probeCount)
        return corrupt(where() + "vertex " + std::to_string(tet.v[i]) + " out of range (" +
                       std::to_string(probeCount) + " probes)");
      for (int j = 0; j < i; ++j)
        if (tet.v[i] == tet.v[j])
          return corrupt(where() + "vertex " + std::to_string(tet.v[i]) + " repeated");
      const int32_t n = tet.n[i];
      if (n < -1 || n >= tetCount || n == t)
        return corrupt(where() + "neighbour " + std::to_string(n) + " out of range (" +
                       std::to_string(tetCount) + " tets)");
      if (n >= 0) {  // adjacency is mutual: the neighbour names this tet back
        const Tet& other = level.tets[size_t(n)];
        if (other.n[0] != t && other.n[1] != t && other.n[2] != t && other.n[3] != t)
          return corrupt(where() + "neighbour " + std::to_string(n) + " does not name it back");
      }
    }
  }
  // Second pass, every index now in range: a neighbour shares the face it is named across and names this tet
  // back across that same face (else walks, which trust the table, would wander: O(tets) per query), and no
  // two probes of a tet sit at one float position (the tet would be flat for good: no weights exist in it;
  // the build refuses these too, buildTetRecords in tetra/). O(T), a few compares per face.
  for (int64_t t = 0; t < tetCount; ++t) {
    const Tet& tet = level.tets[size_t(t)];
    const auto where = [t] { return "tet " + std::to_string(t) + ": "; };
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < i; ++j)
        if (level.probes[size_t(tet.v[i])] == level.probes[size_t(tet.v[j])])
          return corrupt(where() + "flat: probes " + std::to_string(tet.v[j]) + " and " +
                         std::to_string(tet.v[i]) + " are at the same float position");
    for (int i = 0; i < 4 && !linked; ++i) {
      const int32_t n = tet.n[i];
      if (n < 0) continue;
      const Tet& other = level.tets[size_t(n)];
      int opposite = -1, shared = 0;  // other's vertex off this tet's face i, and the face's vertices found
      for (int j = 0; j < 4; ++j) {
        bool onFace = false;
        for (int k = 0; k < 4; ++k) onFace = onFace || (k != i && tet.v[k] == other.v[j]);
        if (onFace)
          ++shared;
        else
          opposite = j;
      }
      if (shared != 3 || other.v[opposite] == tet.v[i])
        return corrupt(where() + "neighbour " + std::to_string(n) + " across face " + std::to_string(i) +
                       " does not share that face");
      if (other.n[opposite] != t)
        return corrupt(where() + "neighbour " + std::to_string(n) + " across face " + std::to_string(i) +
                       " does not name it back across the shared face");
    }
  }
  if (!level.outerCells.empty()) {
    int64_t hullFaces = 0;
    for (const Tet& tet : level.tets)
      for (int f = 0; f < 4; ++f) hullFaces += tet.n[f] < 0;
    const auto cellCount = int64_t(level.outerCells.size());
    if (cellCount != hullFaces)
      return corrupt(std::to_string(cellCount) + " outer cells for " + std::to_string(hullFaces) +
                     " hull faces");
    for (int64_t k = 0; k < cellCount; ++k) {
      const OuterCell& c = level.outerCells[size_t(k)];
      const auto where = [k] { return "outer cell " + std::to_string(k) + ": "; };
      if (c.tet < 0 || c.tet >= tetCount || c.face < 0 || c.face > 3)
        return corrupt(where() + "tet " + std::to_string(c.tet) + " face " + std::to_string(c.face) +
                       " out of range");
      if (k > 0) {  // strictly increasing (tet, face): the order lookups binary-search
        const OuterCell& p = level.outerCells[size_t(k - 1)];
        if (p.tet > c.tet || (p.tet == c.tet && p.face >= c.face))
          return corrupt(where() + "out of (tet, face) order");
      }
      const Tet& tet = level.tets[size_t(c.tet)];
      if (tet.n[c.face] != -1) return corrupt(where() + "names a face that is not on the hull");
      for (int i = 0; i < 3; ++i) {
        bool onFace = false;
        for (int j = 0; j < 4; ++j) onFace = onFace || (j != c.face && tet.v[j] == c.v[i]);
        for (int j = 0; j < i; ++j) onFace = onFace && c.v[j] != c.v[i];
        if (!onFace)
          return corrupt(where() + "probe " + std::to_string(c.v[i]) + " is not a vertex of its hull face");
        const int32_t n = c.n[i];
        if (n < -1 || n >= cellCount || n == k)
          return corrupt(where() + "link " + std::to_string(n) + " out of range");
        if (n >= 0) {
          const OuterCell& o = level.outerCells[size_t(n)];
          if (o.n[0] != k && o.n[1] != k && o.n[2] != k)
            return corrupt(where() + "link " + std::to_string(n) + " does not name it back");
          // The linked cell shares the edge opposite v[i] (the outer walk trusts the links as the tet walk
          // trusts its neighbours).
          const int32_t a = c.v[(i + 1) % 3], b = c.v[(i + 2) % 3];
          const auto has = [&](int32_t v) { return o.v[0] == v || o.v[1] == v || o.v[2] == v; };
          if (!has(a) || !has(b))
            return corrupt(where() + "link " + std::to_string(n) +
                           " does not share the edge opposite probe " + std::to_string(c.v[i]));
        }
        const glm::vec3 nrm(c.normal[i][0], c.normal[i][1], c.normal[i][2]);
        const float len2 = nrm.x * nrm.x + nrm.y * nrm.y + nrm.z * nrm.z;
        if (!finite3(nrm) || !(std::abs(len2 - 1.0f) < 1e-3f) || c.normal[i][3] != 0.0f)
          return corrupt(where() + "normal " + std::to_string(i) + " is not a unit vector");
      }
    }
  }
  const CellGrid& g = level.cellGrid;
  if (!g.slots.empty() || !g.nodes.empty()) {
    const size_t slots = g.slots.size();
    if (slots == 0 || (slots & (slots - 1)) != 0 || slots > kMaxCount || g.nodes.size() > kMaxCount ||
        g.unprovenLeaves > g.leaves)
      return corrupt("cell grid: " + std::to_string(slots) +
                     " slots (a power of two) or counts out of range");
    if (!finite3(g.min) || !(g.cellSize > 0.0f) || !std::isfinite(g.cellSize) || g.maxProbe < 1 ||
        g.maxProbe > kMaxCellProbe)
      return corrupt("cell grid: bad origin, cell size or probe bound");
    const auto nodeCount = int64_t(g.nodes.size());
    // A child is a later node (so every descent ends), a tet in range, or the empty leaf.
    const auto validChild = [&](int32_t c, int64_t parent) {
      if (c >= 0) return int64_t(c) > parent && int64_t(c) < nodeCount;
      return c == kEmptyLeaf || int64_t(~c) < tetCount;
    };
    for (size_t s = 0; s < slots; ++s)
      if (g.slots[s].key[0] != INT32_MIN && !validChild(g.slots[s].root, -1))
        return corrupt("cell grid: slot " + std::to_string(s) + " root out of range");
    for (int64_t n = 0; n < nodeCount; ++n) {
      const BspNode& node = g.nodes[size_t(n)];
      for (float x : node.plane)
        if (!std::isfinite(x)) return corrupt("cell grid: node " + std::to_string(n) + " plane not finite");
      if (!validChild(node.child[0], n) || !validChild(node.child[1], n))
        return corrupt("cell grid: node " + std::to_string(n) + " child out of range");
    }
  }
  if (!level.probeKinds.empty()) {
    if (level.probeKinds.size() != level.probes.size())
      return corrupt("probe kinds: " + std::to_string(level.probeKinds.size()) + " for " +
                     std::to_string(level.probes.size()) + " probes");
    for (size_t i = 0; i < level.probeKinds.size(); ++i)
      if (uint32_t(level.probeKinds[i]) >= kLevelProbeKindCount)
        return corrupt("probe kind of probe " + std::to_string(i) + " is " +
                       std::to_string(uint32_t(level.probeKinds[i])) + ", not a known kind");
  }
  const LevelOcclusion& occ = level.occlusion;
  if (!occ.tets.empty() || !occ.planes.empty() || !occ.shadowMaps.empty()) {
    if (occ.tets.size() != level.tets.size())
      return corrupt("occlusion: " + std::to_string(occ.tets.size()) + " records for " +
                     std::to_string(level.tets.size()) + " tets");
    if (occ.shadowMaps.size() % kShadowMapBlockBytes != 0 || occ.planes.size() > kOcclusionMaxOffset ||
        occ.shadowMaps.size() / kShadowMapBlockBytes > kOcclusionMaxOffset)
      return corrupt("occlusion: plane or shadow-map block count out of range");
    const uint64_t blocks = occ.shadowMaps.size() / kShadowMapBlockBytes;
    uint64_t planesUsed = 0, blocksUsed = 0;
    for (size_t t = 0; t < occ.tets.size(); ++t) {
      const TetOcclusion& rec = occ.tets[t];
      const auto where = [t] { return "occlusion of tet " + std::to_string(t) + ": "; };
      const uint32_t kind = rec.header & 3u;
      if (kind == kOcclusionNone) {
        if (rec.header != 0 || rec.cells != 0) return corrupt(where() + "kind none with non-zero fields");
      } else if (kind == kOcclusionPlanes) {
        const uint32_t count = rec.planeCount();
        const uint32_t usedBits = 4u << count;  // 2^count cells x 4 bits
        if (count == 0 || uint64_t(rec.offset()) + count > occ.planes.size() ||
            (usedBits < 32 && (rec.cells >> usedBits) != 0))
          return corrupt(where() + "plane count, offset or cell masks out of range");
        planesUsed += count;
      } else if (kind == kOcclusionShadowMaps) {
        if (rec.planeCount() != 0 || rec.cells != 0 || rec.offset() >= blocks)
          return corrupt(where() + "shadow-map block out of range");
        ++blocksUsed;
      } else {
        return corrupt(where() + "unknown kind " + std::to_string(kind));
      }
    }
    if (planesUsed != occ.planes.size() || blocksUsed != blocks)
      return corrupt("occlusion: " + std::to_string(occ.planes.size()) + " planes and " +
                     std::to_string(blocks) + " shadow-map blocks, the records use " +
                     std::to_string(planesUsed) + " and " + std::to_string(blocksUsed));
    for (size_t k = 0; k < occ.planes.size(); ++k)
      if (occ.planes[k].isZero())
        return corrupt("occlusion: plane " + std::to_string(k) + " is zero (no plane)");
  }
  return {};
}

}  // namespace

LevelResult validateLevel(const Level& level) {
  return validateLevelChecks(level, false);
}

LevelResult saveLevel(const std::string& path, const Level& level) {
  if (LevelResult v = validateLevel(level); !v)
    return fail(LevelStatus::kWriteFailed, path + ": refusing to write an invalid level: " + v.message);
  // Section payloads, in file order.
  struct Section {
    uint32_t tag;
    uint32_t flags;
    Writer bytes;
  };
  std::vector<Section> sections;
  sections.push_back({kTagProbes, kSectionRequired, {}});
  for (const glm::vec3& p : level.probes) {
    sections.back().bytes.f32(p.x);
    sections.back().bytes.f32(p.y);
    sections.back().bytes.f32(p.z);
  }
  sections.push_back({kTagShHalf, kSectionRequired, {}});
  for (size_t p = 0; p < level.sh.size(); ++p) {
    ShHalf h;
    if (!encodeShHalf(level.sh[p], &h))
      return fail(
          LevelStatus::kWriteFailed,
          path + ": refusing to write an invalid level: probe " + std::to_string(p) +
              " has an SH coefficient beyond the file's half-precision range (|c| > 2.1e9 W/(m^2 sr))");
    for (uint16_t v : h.h) sections.back().bytes.i16(int16_t(v));
  }
  // Tets: vertices only. Neighbours and outer cells are functions of them (linkTetNeighbours on load,
  // buildOuterCells in ProbeQuery), so they are not stored: 16 + 80 x hull faces / tets bytes a tet less.
  // Packed (TETM, about 4 bytes a tet) unless the level is streamed: its loader seeks each tet's fixed
  // TETC record (2-4 bytes an index).
  if (level.stream.empty()) {
    sections.push_back({kTagTetsPacked, kSectionRequired, {}});
    std::string packed;
    runtime_detail::encodeTetProbes(level.tets, packed);
    sections.back().bytes.bytes(packed.data(), packed.size());
  } else {
    sections.push_back({kTagTetsCompact, kSectionRequired, {}});
    const uint32_t indexBytes = levelProbeIndexBytes(level.probes.size());
    for (const Tet& t : level.tets)
      for (int32_t v : t.v) sections.back().bytes.uN(uint32_t(v), indexBytes);
  }
  sections.push_back({kTagGenerator, kSectionRequired, {}});
  sections.back().bytes.bytes(level.generator.data(), level.generator.size());

  if (!level.cellGrid.slots.empty()) {
    const CellGrid& g = level.cellGrid;
    // Packed (CGR4) when every plane is a tet face's and the trees are in preorder. Its leaf codes refer to
    // the neighbours the loader derives (linkTetNeighbours); validateLevel above proved each stored
    // neighbour is the other tet on the same three probes, which is what the loader derives (a stored -1
    // only leaves a leaf code unused).
    std::string packedNodes;
    std::vector<uint32_t> faces;
    if (nodeFaces(level, faces)) runtime_detail::encodeBspNodes(g.nodes, faces, level.tets, packedNodes);
    const bool packed = !packedNodes.empty() || g.nodes.empty();
    sections.push_back({packed ? kTagCellGridPacked : kTagCellGrid, 0, {}});
    Writer& s = sections.back().bytes;
    for (int a = 0; a < 3; ++a) s.f32(g.min[a]);
    s.f32(g.cellSize);
    s.u32(g.maxProbe);
    s.i32(int32_t(g.maxDepth));
    s.f64(g.meanDepth);
    s.u64(g.leaves);
    s.u64(g.unprovenLeaves);
    s.u64(g.slots.size());
    s.u64(g.nodes.size());
    for (const CellSlot& slot : g.slots) {
      for (int32_t k : slot.key) s.i32(k);
      s.i32(slot.root);
    }
    if (packed) {
      s.bytes(packedNodes.data(), packedNodes.size());
    } else {
      for (const BspNode& node : g.nodes) {
        for (float x : node.plane) s.f32(x);
        for (int32_t c : node.child) s.i32(c);
      }
    }
  }

  if (!level.occlusion.empty()) {  // an empty occlusion writes no section: such files stay byte-identical
    const LevelOcclusion& occ = level.occlusion;
    // Packed (OCC2) unless the level is streamed (its loader seeks each tet's fixed-size OCCL record) or the
    // records' offsets are laid out otherwise (kept as they are).
    const bool packed = level.stream.empty() && occlusionPackable(occ);
    // OCC2 is flagged required: a reader that does not know it must refuse the file, not drop the occlusion.
    sections.push_back({packed ? kTagOcclusionPacked : kTagOcclusion, packed ? kSectionRequired : 0, {}});
    Writer& s = sections.back().bytes;
    s.u64(occ.tets.size());
    s.u64(occ.planes.size());
    s.u64(occ.shadowMaps.size() / kShadowMapBlockBytes);
    if (packed) {
      uint64_t cellBytes = 0;
      for (const TetOcclusion& rec : occ.tets)
        if (rec.kind() == kOcclusionPlanes) cellBytes += occlusionCellBytes(rec.planeCount());
      s.u64(cellBytes);
      for (const TetOcclusion& rec : occ.tets) {
        const auto code = uint8_t(rec.header & 15u);  // kind and plane count
        s.bytes(&code, 1);
      }
      for (const TetOcclusion& rec : occ.tets)
        if (rec.kind() == kOcclusionPlanes) s.uN(rec.cells, occlusionCellBytes(rec.planeCount()));
    } else {
      for (const TetOcclusion& rec : occ.tets) {
        s.u32(rec.header);
        s.u32(rec.cells);
      }
    }
    for (const OcclusionPlane& p : occ.planes)
      for (int16_t x : p.c) s.i16(x);
    s.bytes(occ.shadowMaps.data(), occ.shadowMaps.size());
  }

  if (!level.probeKinds.empty()) {  // none recorded writes no section: such files stay byte-identical
    sections.push_back({kTagProbeKinds, 0, {}});
    for (LevelProbeKind k : level.probeKinds) {
      const auto byte = uint8_t(k);
      sections.back().bytes.bytes(&byte, 1);
    }
  }

  if (!level.stream.empty()) {  // streaming index (streaming.h), opaque here; none writes no section
    sections.push_back({kTagStream, 0, {}});
    sections.back().bytes.bytes(level.stream.data(), level.stream.size());
  }

  Writer w;
  w.bytes(kLevelMagic, sizeof kLevelMagic);
  w.u32(kVersion);
  w.u32(kHeaderBytes);
  w.u32(level.content);
  w.u32(level.shOrder);
  w.f64(level.origin.x);
  w.f64(level.origin.y);
  w.f64(level.origin.z);
  w.u64(level.probes.size());
  w.u64(level.tets.size());
  w.u64(level.generator.size());
  w.u32(uint32_t(sections.size()));
  w.u32(w.crcOf(0, kHeaderCrcOffset));
  uint64_t offset = kHeaderBytes + kSectionEntryBytes * sections.size() + 4;
  for (Section& sec : sections) {
    w.u32(sec.tag);
    w.u32(sec.flags);
    w.u64(offset);
    w.u64(sec.bytes.str().size());
    offset += sec.bytes.str().size();
  }
  w.u32(w.crcOf(kHeaderBytes, w.str().size()));
  for (Section& sec : sections) w.bytes(sec.bytes.str().data(), sec.bytes.str().size());
  w.u32(0);
  if (!level.stream.empty()) {
    // The streaming index's checksums (its own and each sector's, over the records as written above:
    // stream_format.h), computed by the reader StreamingLevel uses; an index it cannot read is refused.
    auto* bytes = reinterpret_cast<uint8_t*>(w.str().data());
    LevelFileLayout layout;
    std::string e;
    if (LevelResult r = parseLevelHeader(bytes, w.str().size(), path, layout); !r)
      e = r.message;
    else if (LevelResult t = parseLevelTable(bytes + kHeaderBytes, w.str().size(), path, layout); !t)
      e = t.message;
    else
      e = runtime_detail::sealStreamIndex(bytes, w.str().size(), layout, runtime_detail::StreamSeal::kAll);
    if (!e.empty())
      return fail(LevelStatus::kWriteFailed, path + ": refusing to write an invalid streaming index: " + e);
  }
  w.patchU32(w.str().size() - kTrailerBytes, w.crcOf(kHeaderBytes, w.str().size() - kTrailerBytes));
  std::string error;
  if (!writeFileAtomic(path, w.str(), &error)) return fail(LevelStatus::kWriteFailed, error);
  return {};
}

namespace {

// loadLevelFromMemory's body; allocation failures (a level the file's bytes back but memory cannot hold)
// throw std::bad_alloc out of here and are turned into kTooLarge by the caller.
LevelResult parseLevel(const uint8_t* data, uint64_t size, const std::string& path, Level& out) {
  const std::string name = path + ": ";

  // The header and the section table (level_file.h: the checks every reader shares), the payload
  // checksum, then each known section's size.
  LevelFileLayout layout;
  if (LevelResult e = parseLevelHeader(data, size, path, layout); !e) return e;
  if (LevelResult e = parseLevelTable(data + kHeaderBytes, size, path, layout); !e) return e;
  if (crc32(data + kHeaderBytes, size_t(size - kHeaderBytes - kTrailerBytes)) !=
      Reader(data + size - kTrailerBytes).u32())
    return fail(LevelStatus::kCorrupt, name + "payload checksum mismatch");
  if (LevelResult e = checkLevelSections(layout, path); !e) return e;
  Level level;
  level.content = layout.content;
  level.shOrder = layout.shOrder;
  level.origin = layout.origin;
  const uint64_t probeCount = layout.probeCount, tetCount = layout.tetCount,
                 generatorBytes = layout.generatorBytes;
  const LevelSectionRef &probes = layout.probes, &sh = layout.sh, &shHalf = layout.shHalf,
                        &tets = layout.tets, &tetsCompact = layout.tetsCompact,
                        &tetsPacked = layout.tetsPacked, &generator = layout.generator,
                        &outer = layout.outerCells, &cellGrid = layout.cellGrid,
                        &cellGridPacked = layout.cellGridPacked, &occlusionFixed = layout.occlusion,
                        &occlusionPacked = layout.occlusionPacked, &kinds = layout.probeKinds,
                        &stream = layout.stream;
  const bool tetsLinked = tetsCompact.present || tetsPacked.present;  // neighbours derived on load
  const uint32_t indexBytes = levelProbeIndexBytes(probeCount);

  // The cell grid: nodes with their planes (CGR2) or packed (CGR4: a varint stream, checked as it is decoded).
  const bool gridPacked = cellGridPacked.present;
  const LevelSectionRef& grid = gridPacked ? cellGridPacked : cellGrid;
  uint64_t gridSlots = 0, gridNodes = 0;
  if (grid.present) {
    if (grid.size < kCellGridHeaderBytes)
      return fail(LevelStatus::kCorrupt, name + "cell grid section shorter than its header");
    Reader counts(data + grid.offset + 48);
    gridSlots = counts.u64();
    gridNodes = counts.u64();
    const uint64_t fixed = kCellGridHeaderBytes + gridSlots * kSlotBytes;
    if (gridSlots > kMaxCount || gridNodes > kMaxCount ||
        (gridPacked ? grid.size < fixed + gridNodes : grid.size != fixed + gridNodes * kNodeBytes))
      return fail(LevelStatus::kCorrupt, name + "cell grid section size does not match its counts");
  }

  // Occlusion: fixed 8-byte records with their offsets (OCCL) or packed (OCC2, what saveLevel writes).
  const bool occPacked = occlusionPacked.present;
  const LevelSectionRef& occlusion = occPacked ? occlusionPacked : occlusionFixed;
  uint64_t occTets = 0, occPlanes = 0, occBlocks = 0, occCellBytes = 0;
  if (occlusion.present) {
    const uint64_t headerBytes = occPacked ? kOcclusionPackedHeaderBytes : kOcclusionHeaderBytes;
    if (occlusion.size < headerBytes)
      return fail(LevelStatus::kCorrupt, name + "occlusion section shorter than its header");
    Reader counts(data + occlusion.offset);
    occTets = counts.u64();
    occPlanes = counts.u64();
    occBlocks = counts.u64();
    if (occPacked) occCellBytes = counts.u64();
    const uint64_t recordBytes = occPacked ? occTets + occCellBytes : occTets * kTetOcclusionBytes;
    if (occTets != tetCount || occPlanes > kOcclusionMaxOffset || occBlocks > kOcclusionMaxOffset ||
        occCellBytes > 4 * occTets ||
        occlusion.size !=
            headerBytes + recordBytes + occPlanes * kOcclusionPlaneBytes + occBlocks * kShadowMapBlockBytes)
      return fail(LevelStatus::kCorrupt, name + "occlusion section size does not match its counts");
  }

  // The streaming index (kept as bytes): its structure, its CRC and each sector's, as StreamingLevel reads
  // them (stream_format.h), so a file one loader accepts the other does too.
  if (stream.present)
    if (std::string e = runtime_detail::checkStreamIndex(data, size_t(size), layout); !e.empty())
      return fail(LevelStatus::kCorrupt, name + e);

  // Sizes are now known to be backed by the file: allocate and parse.
  Reader body(data + probes.offset);
  level.probes.resize(size_t(probeCount));
  for (size_t i = 0; i < level.probes.size(); ++i) {
    glm::vec3& p = level.probes[i];
    p.x = body.f32();
    p.y = body.f32();
    p.z = body.f32();
    // Checked here as validateLevel does: the grid's planes are computed from positions before it runs,
    // and a NaN would be reported as a flat face instead of as what it is.
    if (std::string e = positionError(p, i); !e.empty()) return fail(LevelStatus::kCorrupt, name + e);
  }
  level.sh.resize(size_t(probeCount));
  if (shHalf.present) {
    body = Reader(data + shHalf.offset);
    for (size_t p = 0; p < level.sh.size(); ++p) {
      ShHalf h;
      for (uint16_t& v : h.h) v = uint16_t(body.i16());
      bool valid = true;
      level.sh[p] = decodeShHalf(h, &valid);
      if (!valid)
        return fail(LevelStatus::kCorrupt,
                    name + "probe " + std::to_string(p) +
                        ": SH record holds a non-finite value or a scale that is not a "
                        "power of two in [2^-24, 2^15]");
    }
  } else {
    body = Reader(data + sh.offset);
    for (ShRgb& s : level.sh)
      for (glm::vec3& c : s.c) {
        c.x = body.f32();
        c.y = body.f32();
        c.z = body.f32();
      }
  }
  level.tets.resize(size_t(tetCount));
  if (tetsPacked.present) {
    // Range and repeat checks as it decodes (linkTetNeighbours' precondition).
    if (std::string e = runtime_detail::decodeTetProbes(data + tetsPacked.offset, size_t(tetsPacked.size),
                                                        size_t(tetCount), size_t(probeCount), level.tets);
        !e.empty())
      return fail(LevelStatus::kCorrupt, name + e);
    if (std::string e = linkTetNeighbours(level.tets, size_t(probeCount)); !e.empty())
      return fail(LevelStatus::kCorrupt, name + e);
  } else if (tetsCompact.present) {
    body = Reader(data + tetsCompact.offset);
    for (size_t t = 0; t < level.tets.size(); ++t) {
      Tet& tet = level.tets[t];
      for (int i = 0; i < 4; ++i) {
        const uint32_t v = body.uN(indexBytes);
        tet.v[i] = int32_t(v);
        tet.n[i] = -1;
        // linkTetNeighbours' precondition (validateLevelChecks skips them, and the neighbour checks, for
        // tets linked here).
        if (v >= probeCount)
          return fail(LevelStatus::kCorrupt, name + "tet " + std::to_string(t) + ": vertex " +
                                                 std::to_string(tet.v[i]) + " out of range (" +
                                                 std::to_string(probeCount) + " probes)");
        for (int j = 0; j < i; ++j)
          if (tet.v[i] == tet.v[j])
            return fail(LevelStatus::kCorrupt, name + "tet " + std::to_string(t) + ": vertex " +
                                                   std::to_string(tet.v[i]) + " repeated");
      }
    }
    if (std::string e = linkTetNeighbours(level.tets, size_t(probeCount)); !e.empty())
      return fail(LevelStatus::kCorrupt, name + e);
  } else {
    body = Reader(data + tets.offset);
    for (Tet& t : level.tets) {
      for (int32_t& v : t.v) v = body.i32();
      for (int32_t& n : t.n) n = body.i32();
    }
  }
  level.generator.assign(reinterpret_cast<const char*>(data + generator.offset), size_t(generatorBytes));
  if (outer.present) {
    body = Reader(data + outer.offset);
    level.outerCells.resize(size_t(outer.size / kOuterCellBytes));
    for (OuterCell& c : level.outerCells) {
      for (int32_t& v : c.v) v = body.i32();
      c.tet = body.i32();
      for (int32_t& n : c.n) n = body.i32();
      c.face = body.i32();
      for (auto& n : c.normal) {
        for (int a = 0; a < 3; ++a) n[a] = body.f32();
        n[3] = 0.0f;
        // Onto the octahedral lattice the GPU receives (oct_normal.h), so CPU and GPU answers agree on an
        // old file's stored cells too (only unit normals: the validation after refuses the others).
        const glm::dvec3 raw(n[0], n[1], n[2]);
        if (std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2]) &&
            std::abs(glm::dot(raw, raw) - 1.0) < 1e-3) {
          const glm::vec3 q = quantizeOctNormal(raw);
          for (int a = 0; a < 3; ++a) n[a] = q[a];
        }
      }
      for (int pad = 0; pad < 3; ++pad)
        if (body.u32() != 0) return fail(LevelStatus::kCorrupt, name + "outer cell padding is not zero");
    }
  }

  if (grid.present) {
    CellGrid& g = level.cellGrid;
    body = Reader(data + grid.offset);
    for (int a = 0; a < 3; ++a) g.min[a] = body.f32();
    g.cellSize = body.f32();
    g.maxProbe = body.u32();
    g.maxDepth = body.i32();
    g.meanDepth = body.f64();
    g.leaves = size_t(body.u64());
    g.unprovenLeaves = size_t(body.u64());
    body.skip(16);  // the counts, read above
    g.slots.resize(size_t(gridSlots));
    for (CellSlot& slot : g.slots) {
      for (int32_t& k : slot.key) k = body.i32();
      slot.root = body.i32();
    }
    if (gridPacked) {
      // The planes are recomputed from the faces, as buildCellGrid computed them (cellGridFacePlane).
      const uint64_t at = kCellGridHeaderBytes + gridSlots * kSlotBytes;
      if (std::string e =
              runtime_detail::decodeBspNodes(data + grid.offset + at, size_t(grid.size - at),
                                             size_t(gridNodes), level.tets, level.probes, g.nodes);
          !e.empty())
        return fail(LevelStatus::kCorrupt, name + e);
    } else {
      g.nodes.resize(size_t(gridNodes));
      for (BspNode& node : g.nodes) {
        for (float& x : node.plane) x = body.f32();
        for (int32_t& c : node.child) c = body.i32();
      }
    }
  }

  if (occlusion.present) {
    LevelOcclusion& occ = level.occlusion;
    occ.tets.resize(size_t(occTets));
    if (!occPacked) {  // OCCL: the records as stored
      body = Reader(data + occlusion.offset + kOcclusionHeaderBytes);
      for (TetOcclusion& rec : occ.tets) {
        rec.header = body.u32();
        rec.cells = body.u32();
      }
    } else {
      // OCC2: the records from their codes. Offsets follow from the order, each checked against the counts
      // before it is used (validateLevel repeats the record checks on the result).
      const uint8_t* codes = data + occlusion.offset + kOcclusionPackedHeaderBytes;
      Reader cells(codes + occTets);
      uint64_t planes = 0, blocks = 0, cellBytes = 0;
      for (size_t t = 0; t < occ.tets.size(); ++t) {
        const uint32_t code = codes[t], kind = code & 3u, count = code >> 2;
        const auto where = [&] { return name + "occlusion of tet " + std::to_string(t) + ": "; };
        if (kind == kOcclusionNone && code == 0) {
          occ.tets[t] = TetOcclusion{};
        } else if (kind == kOcclusionPlanes && count >= 1 && count <= 3) {
          const uint32_t n = occlusionCellBytes(count);
          if (planes + count > occPlanes || cellBytes + n > occCellBytes)
            return fail(LevelStatus::kCorrupt,
                        where() + "its planes or cell masks run past the section's counts");
          occ.tets[t] = makeTetOcclusion(kOcclusionPlanes, count, uint32_t(planes), cells.uN(n));
          planes += count;
          cellBytes += n;
        } else if (kind == kOcclusionShadowMaps && count == 0) {
          if (blocks >= occBlocks)
            return fail(LevelStatus::kCorrupt,
                        where() + "its shadow-map block runs past the section's counts");
          occ.tets[t] = makeTetOcclusion(kOcclusionShadowMaps, 0, uint32_t(blocks), 0);
          ++blocks;
        } else {
          return fail(LevelStatus::kCorrupt, where() + "unknown code " + std::to_string(code));
        }
      }
      if (planes != occPlanes || blocks != occBlocks || cellBytes != occCellBytes)
        return fail(LevelStatus::kCorrupt,
                    name + "occlusion: " + std::to_string(occPlanes) + " planes, " +
                        std::to_string(occBlocks) + " shadow-map blocks and " + std::to_string(occCellBytes) +
                        " cell-mask bytes, the records use " + std::to_string(planes) + ", " +
                        std::to_string(blocks) + " and " + std::to_string(cellBytes));
      body = Reader(codes + occTets + occCellBytes);
    }
    occ.planes.resize(size_t(occPlanes));
    for (OcclusionPlane& p : occ.planes)
      for (int16_t& x : p.c) x = body.i16();
    occ.shadowMaps.resize(size_t(occBlocks * kShadowMapBlockBytes));
    if (!occ.shadowMaps.empty())
      std::memcpy(occ.shadowMaps.data(), body.skip(occ.shadowMaps.size()), occ.shadowMaps.size());
  }

  if (kinds.present) {
    const auto* k = data + kinds.offset;
    level.probeKinds.resize(size_t(probeCount));
    for (size_t i = 0; i < level.probeKinds.size(); ++i) level.probeKinds[i] = LevelProbeKind(k[i]);
  }

  if (stream.present) {  // kept as bytes; StreamingLevel (streaming.cpp) parses and checks it
    const auto* b = data + stream.offset;
    level.stream.assign(b, b + stream.size);
  }

  if (LevelResult v = validateLevelChecks(level, tetsLinked); !v) return fail(v.status, name + v.message);
  out = std::move(level);
  return {};
}

}  // namespace

LevelResult loadLevelFromMemory(const void* bytes, size_t size, const std::string& name, Level& out) {
  out = Level{};
  try {
    const LevelResult r = parseLevel(static_cast<const uint8_t*>(bytes), size, name, out);
    if (!r) out = Level{};
    return r;
  } catch (const std::exception&) {  // bad_alloc or length_error: nothing else in the parse throws
    out = Level{};
    return fail(LevelStatus::kTooLarge,
                name + ": cannot allocate memory for a level of " + std::to_string(size) + " bytes");
  }
}

LevelResult loadLevel(const std::string& path, Level& out, uint64_t maxBytes) {
  out = Level{};
  std::vector<char> file;
  std::string error;
  bool tooLarge = false;
  if (!readFile(path, file, &error, maxBytes, &tooLarge))
    return fail(tooLarge ? LevelStatus::kTooLarge : LevelStatus::kCannotOpen, error);
  return loadLevelFromMemory(file.data(), file.size(), path, out);
}

}  // namespace tetraprobe
