// Streaming a level by sector (streaming.h, docs/streaming.md): open checks the file and reads the STRM
// index and the coarse probe set; load reads one sector's records (tets, their probes and SH, occlusion,
// the cell's BSP) with seeks into the level's own sections; the loaded sectors are joined into one small
// Level (indices renumbered, neighbours outside it cut to -1, the loaded cells' BSPs under a new hash table)
// and queried by an ordinary ProbeQuery. Where a point's cell is loaded and the point lies in a tet, that
// tet, the cell's BSP leaf's tet, the neighbours the walk steps to, their probes and occlusion are all
// loaded (their bounding boxes touch the cell), so the query runs the same operations on the same numbers
// as on the full level. Outside every tet the full level answers from its outer cells, which a loaded part
// does not hold: the coarse set answers there.
#include "tetraprobe/runtime/streaming.h"

#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/runtime/tet_adjacency.h"

#include <algorithm>
#include <bit>
#include <climits>
#include <cmath>
#include <cstring>
#include <fstream>

#include "crc32.h"

namespace tetraprobe {

namespace {

using runtime_detail::crc32;
using runtime_detail::crc32Update;

constexpr uint8_t kMagic[8] = {0x89, 'T', 'P', 'B', '\r', '\n', 0x1a, '\n'};
constexpr uint32_t kVersion = kLevelFormatVersion, kHeaderBytes = 80, kMaxSections = 64;
constexpr uint64_t kMaxCount = uint64_t(INT32_MAX);
constexpr uint32_t kStreamVersion = 1;
constexpr uint64_t kStreamHeaderBytes = 64, kSectorBytes = 40;

constexpr uint32_t tag(const char (&s)[5]) {
  return uint32_t(uint8_t(s[0])) | uint32_t(uint8_t(s[1])) << 8 | uint32_t(uint8_t(s[2])) << 16 |
         uint32_t(uint8_t(s[3])) << 24;
}

uint32_t u32At(const uint8_t* p) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= uint32_t(p[i]) << (8 * i);
  return v;
}
uint64_t u64At(const uint8_t* p) {
  return uint64_t(u32At(p)) | uint64_t(u32At(p + 4)) << 32;
}
uint32_t uintAt(const uint8_t* p, uint64_t bytes) {  // little-endian, 1..4 bytes
  uint32_t v = 0;
  for (uint64_t b = 0; b < bytes; ++b) v |= uint32_t(p[b]) << (8 * b);
  return v;
}
int32_t i32At(const uint8_t* p) {
  return int32_t(u32At(p));
}
float f32At(const uint8_t* p) {
  return std::bit_cast<float>(u32At(p));
}

LevelResult fail(LevelStatus s, std::string message) {
  return LevelResult{s, std::move(message)};
}

// One sector's record in the index.
struct SectorRecord {
  int32_t key[3];
  int32_t root;
  uint32_t tetFirst, tetCount, probeFirst, probeCount, nodeFirst, nodeCount;
};

SectorRecord sectorRecord(const std::vector<uint8_t>& index, size_t s) {
  const uint8_t* p = index.data() + kStreamHeaderBytes + kSectorBytes * s;
  SectorRecord r;
  for (int a = 0; a < 3; ++a) r.key[a] = i32At(p + 4 * a);
  r.root = i32At(p + 12);
  r.tetFirst = u32At(p + 16);
  r.tetCount = u32At(p + 20);
  r.probeFirst = u32At(p + 24);
  r.probeCount = u32At(p + 28);
  r.nodeFirst = u32At(p + 32);
  r.nodeCount = u32At(p + 36);
  return r;
}

size_t levelBytes(const Level& l) {
  return l.probes.size() * sizeof(glm::vec3) + l.sh.size() * sizeof(ShRgb) + l.tets.size() * sizeof(Tet) +
         l.outerCells.size() * sizeof(OuterCell) + cellGridBytes(l.cellGrid) + l.occlusion.bytes() +
         l.probeKinds.size() + l.generator.size() + l.stream.size();
}

// What a ProbeQuery builds beside its level: the start grid, and the outer cells and cell grid when the
// level carries none.
size_t queryBytes(const ProbeQuery& q) {
  size_t n = q.startGrid().startTet.size() * sizeof(int32_t);
  if (q.level().outerCells.empty()) n += q.outerCells().size() * sizeof(OuterCell);
  if (q.level().cellGrid.slots.empty()) n += cellGridBytes(q.cellGrid());
  return n;
}

size_t indexOf(const std::vector<uint32_t>& sorted, uint32_t v) {
  return size_t(std::lower_bound(sorted.begin(), sorted.end(), v) - sorted.begin());
}

}  // namespace

// The level file's sections the sectors read from, and the open stream.
struct StreamingLevel::File {
  std::ifstream in;
  uint64_t probes = 0, sh = 0, tets = 0;  // section offsets
  // Tet bytes: 4 x levelProbeIndexBytes (TETC, probes) or 32 (TETS, with neighbours).
  uint64_t tetRecord = 32;
  uint64_t shRecord = 108;  // SH bytes a probe: 108 (SHRG, float) or 56 (SHRH, ShHalf)
  uint64_t occl = 0;        // 0: no occlusion section
  uint64_t strm = 0;        // the streaming index section
  uint64_t probeCount = 0, tetCount = 0, planeCount = 0, blockCount = 0;
  uint32_t content = 0, shOrder = 2;

  bool read(uint64_t at, void* out, size_t n) {
    in.seekg(std::streamoff(at));
    in.read(static_cast<char*>(out), std::streamsize(n));
    return bool(in);
  }
};

// One loaded sector: its records with the file's (global) indices.
struct StreamingLevel::Sector {
  std::vector<uint32_t> tetIds, probeIds;  // increasing
  std::vector<Tet> tets;                   // global probe and neighbour indices
  std::vector<glm::vec3> positions;
  std::vector<ShRgb> sh;
  std::vector<TetOcclusion> occ;       // empty without occlusion
  std::vector<OcclusionPlane> planes;  // the sector's tets' planes, in tet order
  std::vector<uint8_t> blocks;         // their shadow-map blocks, in tet order
  std::vector<BspNode> nodes;          // children >= 0 index `nodes`; leaves name global tets
  int32_t root = kEmptyLeaf;
  size_t bytes() const {
    return (tetIds.size() + probeIds.size()) * 4 + tets.size() * sizeof(Tet) +
           positions.size() * sizeof(glm::vec3) + sh.size() * sizeof(ShRgb) +
           occ.size() * sizeof(TetOcclusion) + planes.size() * sizeof(OcclusionPlane) + blocks.size() +
           nodes.size() * sizeof(BspNode);
  }
};

StreamingLevel::StreamingLevel() = default;
StreamingLevel::~StreamingLevel() = default;

void StreamingLevel::close() {
  file_.reset();
  keys_.clear();
  index_.clear();
  coarse_ = Level{};
  coarseQuery_.reset();
  loaded_.clear();
  fine_ = Level{};
  fineQuery_.reset();
}

LevelResult StreamingLevel::open(const std::string& path) {
  close();
  path_ = path;
  const std::string name = path + ": ";
  auto f = std::make_unique<File>();
  f->in.open(path, std::ios::binary);
  if (!f->in) return fail(LevelStatus::kCannotOpen, name + "cannot open");
  f->in.seekg(0, std::ios::end);
  const uint64_t size = uint64_t(f->in.tellg());
  uint8_t h[kHeaderBytes];
  if (size < kHeaderBytes || !f->read(0, h, kHeaderBytes))
    return fail(LevelStatus::kTruncated, name + "truncated header");
  if (std::memcmp(h, kMagic, 8) != 0) return fail(LevelStatus::kNotALevel, name + "not a tetraprobe level");
  if (u32At(h + 8) != kVersion)
    return fail(LevelStatus::kUnsupportedVersion, name + "format version " + std::to_string(u32At(h + 8)));
  if (crc32(h, 76) != u32At(h + 76)) return fail(LevelStatus::kCorrupt, name + "header checksum mismatch");
  f->content = u32At(h + 16);
  f->shOrder = u32At(h + 20);
  for (int a = 0; a < 3; ++a) origin_[a] = std::bit_cast<double>(u64At(h + 24 + 8 * a));
  f->probeCount = u64At(h + 48);
  f->tetCount = u64At(h + 56);
  const uint32_t sections = u32At(h + 72);
  if (u32At(h + 12) != kHeaderBytes || sections > kMaxSections || f->probeCount > kMaxCount ||
      f->tetCount > kMaxCount)
    return fail(LevelStatus::kCorrupt, name + "implausible header");
  const uint64_t tableEnd = kHeaderBytes + 24ull * sections + 4;
  std::vector<uint8_t> table(size_t(tableEnd - kHeaderBytes));
  if (size < tableEnd + 4 || !f->read(kHeaderBytes, table.data(), table.size()))
    return fail(LevelStatus::kTruncated, name + "truncated section table");
  if (crc32(table.data(), table.size() - 4) != u32At(table.data() + table.size() - 4))
    return fail(LevelStatus::kCorrupt, name + "section table checksum mismatch");
  uint64_t expected = tableEnd, probesSize = 0, shSize = 0, tetsSize = 0, occlSize = 0, strm = 0,
           strmSize = 0;
  bool haveProbes = false, haveSh = false, haveTets = false;
  for (uint32_t i = 0; i < sections; ++i) {
    const uint8_t* e = table.data() + 24 * i;
    const uint32_t t = u32At(e);
    const uint64_t offset = u64At(e + 8), bytes = u64At(e + 16);
    if (offset != expected || bytes > (uint64_t(1) << 40))
      return fail(LevelStatus::kCorrupt, name + "section " + std::to_string(i) + ": bad offset or size");
    expected += bytes;
    if (t == tag("PRBS")) f->probes = offset, probesSize = bytes, haveProbes = true;
    if (t == tag("SHRG") || t == tag("SHRH")) {
      if (haveSh) return fail(LevelStatus::kCorrupt, name + "more than one SH section");
      f->sh = offset, shSize = bytes, haveSh = true;
      f->shRecord = t == tag("SHRH") ? sizeof(ShHalf) : sizeof(ShRgb);
    }
    if (t == tag("TETS") || t == tag("TETC")) {
      if (haveTets) return fail(LevelStatus::kCorrupt, name + "more than one tet section");
      f->tets = offset, tetsSize = bytes, haveTets = true;
      f->tetRecord = t == tag("TETC") ? 4 * levelProbeIndexBytes(f->probeCount) : 32;
    }
    if (t == tag("TETM"))  // saveLevel writes TETC for a level with a streaming index: load seeks its records
      return fail(LevelStatus::kCorrupt,
                  name + "packed tets (TETM) cannot be streamed: re-run tetraprobe stream");
    if (t == tag("OCCL")) f->occl = offset, occlSize = bytes;
    if (t == tag("OCC2"))  // saveLevel writes OCCL for a level with a streaming index: load seeks its records
      return fail(LevelStatus::kCorrupt,
                  name + "packed occlusion (OCC2) cannot be streamed: re-run tetraprobe stream");
    if (t == tag("STRM")) strm = offset, strmSize = bytes;
  }
  if (expected + 4 != size)
    return fail(size < expected + 4 ? LevelStatus::kTruncated : LevelStatus::kCorrupt,
                name + "file size does not match the section table");
  if (!haveProbes || !haveSh || !haveTets || probesSize != 12 * f->probeCount ||
      shSize != f->shRecord * f->probeCount || tetsSize != f->tetRecord * f->tetCount)
    return fail(LevelStatus::kCorrupt, name + "probe, SH or tet section missing or mis-sized");
  // The payload checksum, in pieces: the records load() reads later are the ones checked here.
  {
    std::vector<uint8_t> buf(1 << 16);
    uint32_t crc = 0;
    f->in.seekg(std::streamoff(kHeaderBytes));
    for (uint64_t left = size - 4 - kHeaderBytes; left > 0;) {
      const size_t n = size_t(std::min<uint64_t>(left, buf.size()));
      if (!f->in.read(reinterpret_cast<char*>(buf.data()), std::streamsize(n)))
        return fail(LevelStatus::kTruncated, name + "read failed");
      crc = crc32Update(crc, buf.data(), n);
      left -= n;
    }
    uint8_t trailer[4];
    if (!f->read(size - 4, trailer, 4) || crc != u32At(trailer))
      return fail(LevelStatus::kCorrupt, name + "payload checksum mismatch");
  }
  if (f->occl != 0) {
    uint8_t c[24];
    if (occlSize < 24 || !f->read(f->occl, c, 24)) return fail(LevelStatus::kCorrupt, name + "bad occlusion");
    f->planeCount = u64At(c + 8);
    f->blockCount = u64At(c + 16);
    if (u64At(c) != f->tetCount || f->planeCount > kOcclusionMaxOffset ||
        f->blockCount > kOcclusionMaxOffset ||
        occlSize != 24 + 8 * f->tetCount + 8 * f->planeCount + 64 * f->blockCount)
      return fail(LevelStatus::kCorrupt, name + "occlusion section size does not match its counts");
  }
  if (strm == 0) return fail(LevelStatus::kCorrupt, name + "no streaming index (add one: tetraprobe stream)");

  // The index: header, sector records, tet and probe references, nodes, coarse set.
  // Held: the header and the sector records. A sector's references and nodes are read when it is loaded.
  index_.resize(size_t(kStreamHeaderBytes));
  if (strmSize < kStreamHeaderBytes || !f->read(strm, index_.data(), index_.size()))
    return fail(LevelStatus::kCorrupt, name + "streaming index shorter than its header");
  const uint32_t sectorCount = u32At(index_.data() + 4);
  if (kStreamHeaderBytes + kSectorBytes * sectorCount > strmSize)
    return fail(LevelStatus::kCorrupt, name + "streaming index shorter than its sector records");
  index_.resize(size_t(kStreamHeaderBytes + kSectorBytes * sectorCount));
  if (!f->read(strm + kStreamHeaderBytes, index_.data() + kStreamHeaderBytes,
               index_.size() - kStreamHeaderBytes))
    return fail(LevelStatus::kCannotOpen, name + "read failed");
  f->strm = strm;
  const uint8_t* x = index_.data();
  for (int a = 0; a < 3; ++a) grid_.min[a] = f32At(x + 8 + 4 * a);
  grid_.cellSize = f32At(x + 20);
  const uint64_t tetRefs = u64At(x + 24), probeRefs = u64At(x + 32), nodes = u64At(x + 40);
  const uint64_t coarseProbes = u32At(x + 48), coarseTets = u32At(x + 52);
  if (u32At(x) != kStreamVersion || tetRefs > (uint64_t(1) << 36) || probeRefs > (uint64_t(1) << 36) ||
      nodes > kMaxCount || coarseProbes > kMaxCount || coarseTets > kMaxCount ||
      strmSize != kStreamHeaderBytes + kSectorBytes * sectorCount + 4 * tetRefs + 4 * probeRefs + 24 * nodes +
                      120 * coarseProbes + 32 * coarseTets ||
      !(grid_.cellSize > 0.0f) || !std::isfinite(grid_.cellSize) || !std::isfinite(grid_.min.x) ||
      !std::isfinite(grid_.min.y) || !std::isfinite(grid_.min.z))
    return fail(LevelStatus::kCorrupt, name + "streaming index header does not match its size");
  const uint64_t refsAt = kStreamHeaderBytes + kSectorBytes * sectorCount;
  const uint64_t nodesAt = refsAt + 4 * (tetRefs + probeRefs), coarseAt = nodesAt + 24 * nodes;
  for (uint32_t s = 0; s < sectorCount; ++s) {
    const SectorRecord r = sectorRecord(index_, s);
    const SectorKey key{r.key[0], r.key[1], r.key[2]};
    const std::string where = name + "streaming sector " + std::to_string(s) + ": ";
    if (s > 0 && !(keys_.back() < key)) return fail(LevelStatus::kCorrupt, where + "keys not increasing");
    if (uint64_t(r.tetFirst) + r.tetCount > tetRefs || uint64_t(r.probeFirst) + r.probeCount > probeRefs ||
        uint64_t(r.nodeFirst) + r.nodeCount > nodes)
      return fail(LevelStatus::kCorrupt, where + "ranges out of bounds");
    keys_.push_back(key);
  }

  // The coarse set: a level of its own (no occlusion, no grid: its query builds one).
  coarse_.content = f->content;
  coarse_.shOrder = f->shOrder;
  coarse_.origin = origin_;
  std::vector<uint8_t> coarseBytes(size_t(120 * coarseProbes + 32 * coarseTets));
  if (!f->read(strm + coarseAt, coarseBytes.data(), coarseBytes.size()))
    return fail(LevelStatus::kCannotOpen, name + "read failed");
  const uint8_t* c = coarseBytes.data();
  coarse_.probes.resize(size_t(coarseProbes));
  coarse_.sh.resize(size_t(coarseProbes));
  coarse_.tets.resize(size_t(coarseTets));
  for (glm::vec3& p : coarse_.probes) {
    for (int a = 0; a < 3; ++a) p[a] = f32At(c + 4 * a);
    c += 12;
  }
  for (ShRgb& s : coarse_.sh)
    for (glm::vec3& v : s.c) {
      for (int a = 0; a < 3; ++a) v[a] = f32At(c + 4 * a);
      c += 12;
    }
  for (Tet& t : coarse_.tets) {
    for (int k = 0; k < 4; ++k) t.v[k] = i32At(c + 4 * k);
    for (int k = 0; k < 4; ++k) t.n[k] = i32At(c + 16 + 4 * k);
    c += 32;
  }
  if (coarse_.tets.empty()) return fail(LevelStatus::kCorrupt, name + "streaming index: empty coarse set");
  if (LevelResult v = validateLevel(coarse_); !v)
    return fail(LevelStatus::kCorrupt, name + "streaming coarse set: " + v.message);
  coarseQuery_ = std::make_unique<ProbeQuery>(coarse_, grid_.cellSize, 1);
  file_ = std::move(f);
  return {};
}

SectorKey StreamingLevel::sectorOf(const glm::dvec3& world) const {
  int32_t key[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
  cellGridKey(grid_, world - origin_, key);
  return SectorKey{key[0], key[1], key[2]};
}

bool StreamingLevel::hasSector(const SectorKey& key) const {
  return std::binary_search(keys_.begin(), keys_.end(), key);
}

LevelResult StreamingLevel::load(const SectorKey& key) {
  if (!file_) return fail(LevelStatus::kCannotOpen, "streaming level not open");
  if (isLoaded(key)) return {};
  const auto it = std::lower_bound(keys_.begin(), keys_.end(), key);
  const std::string where = path_ + ": sector (" + std::to_string(key.x) + ", " + std::to_string(key.y) +
                            ", " + std::to_string(key.z) + "): ";
  if (it == keys_.end() || !(*it == key)) return fail(LevelStatus::kCorrupt, where + "not in the index");
  const SectorRecord r = sectorRecord(index_, size_t(it - keys_.begin()));
  const uint8_t* x = index_.data();
  const uint32_t sectorCount = u32At(x + 4);
  const uint64_t tetRefs = u64At(x + 24), probeRefs = u64At(x + 32);
  const uint64_t refsAt = kStreamHeaderBytes + kSectorBytes * sectorCount;
  const uint64_t nodesAt = refsAt + 4 * (tetRefs + probeRefs);
  File& f = *file_;
  auto s = std::make_unique<Sector>();
  auto bad = [&](const std::string& why) { return fail(LevelStatus::kCorrupt, where + why); };
  // The sector's references and nodes, from the index in the file.
  std::vector<uint8_t> refs(4 * (size_t(r.tetCount) + r.probeCount)), nodeBytes(24 * size_t(r.nodeCount));
  if (!f.read(f.strm + refsAt + 4ull * r.tetFirst, refs.data(), 4 * size_t(r.tetCount)) ||
      !f.read(f.strm + refsAt + 4 * (tetRefs + r.probeFirst), refs.data() + 4 * size_t(r.tetCount),
              4 * size_t(r.probeCount)) ||
      !f.read(f.strm + nodesAt + 24ull * r.nodeFirst, nodeBytes.data(), nodeBytes.size()))
    return fail(LevelStatus::kCannotOpen, where + "read failed");
  for (uint32_t k = 0; k < r.tetCount; ++k) s->tetIds.push_back(u32At(refs.data() + 4 * k));
  for (uint32_t k = 0; k < r.probeCount; ++k)
    s->probeIds.push_back(u32At(refs.data() + 4 * (r.tetCount + k)));
  for (size_t k = 0; k < s->tetIds.size(); ++k)
    if (s->tetIds[k] >= f.tetCount || (k > 0 && s->tetIds[k] <= s->tetIds[k - 1]))
      return bad("tet references out of range or not increasing");
  for (size_t k = 0; k < s->probeIds.size(); ++k)
    if (s->probeIds[k] >= f.probeCount || (k > 0 && s->probeIds[k] <= s->probeIds[k - 1]))
      return bad("probe references out of range or not increasing");
  // Nodes: children >= 0 are later nodes of this sector, leaves name tets of this sector.
  auto validChild = [&](int32_t c, int64_t parent) {
    if (c >= 0) return int64_t(c) > parent && int64_t(c) < int64_t(r.nodeCount);
    return c == kEmptyLeaf || std::binary_search(s->tetIds.begin(), s->tetIds.end(), uint32_t(~c));
  };
  if (!validChild(r.root, -1)) return bad("BSP root out of range");
  s->root = r.root;
  s->nodes.resize(r.nodeCount);
  for (uint32_t k = 0; k < r.nodeCount; ++k) {
    const uint8_t* p = nodeBytes.data() + 24 * size_t(k);
    BspNode& n = s->nodes[k];
    for (int a = 0; a < 4; ++a) n.plane[a] = f32At(p + 4 * a);
    n.child[0] = i32At(p + 16);
    n.child[1] = i32At(p + 20);
    if (!validChild(n.child[0], k) || !validChild(n.child[1], k)) return bad("BSP child out of range");
  }
  // The records, read where the level keeps them.
  uint8_t buf[108];
  for (uint32_t t : s->tetIds) {
    const uint64_t indexBytes = f.tetRecord == 32 ? 4 : f.tetRecord / 4;  // TETS: i32 probes, then neighbours
    if (!f.read(f.tets + f.tetRecord * t, buf, size_t(4 * indexBytes)))
      return fail(LevelStatus::kCannotOpen, where + "read failed");
    Tet rec;  // neighbours: linked among the loaded tets when the fine level is assembled
    for (int k = 0; k < 4; ++k)
      rec.v[k] = int32_t(uintAt(buf + indexBytes * uint64_t(k), indexBytes)), rec.n[k] = -1;
    for (int k = 0; k < 4; ++k) {
      const int32_t v = rec.v[k];
      if (v < 0 || !std::binary_search(s->probeIds.begin(), s->probeIds.end(), uint32_t(v)))
        return bad("tet " + std::to_string(t) + " names a probe outside the sector");
      for (int j = 0; j < k; ++j)
        if (rec.v[j] == v) return bad("tet " + std::to_string(t) + " repeats probe " + std::to_string(v));
    }
    s->tets.push_back(rec);
  }
  for (uint32_t p : s->probeIds) {
    if (!f.read(f.probes + 12ull * p, buf, 12)) return fail(LevelStatus::kCannotOpen, where + "read failed");
    s->positions.emplace_back(f32At(buf), f32At(buf + 4), f32At(buf + 8));
    if (!f.read(f.sh + f.shRecord * p, buf, size_t(f.shRecord)))
      return fail(LevelStatus::kCannotOpen, where + "read failed");
    ShRgb sh;
    if (f.shRecord == sizeof(ShHalf)) {
      ShHalf h;
      for (int k = 0; k < 28; ++k) h.h[k] = uint16_t(buf[2 * k] | buf[2 * k + 1] << 8);
      bool valid = true;
      sh = decodeShHalf(h, &valid);
      if (!valid) return bad("probe " + std::to_string(p) + ": SH record is not valid half precision");
    } else {
      for (int i = 0; i < kShCoeffCount; ++i)
        for (int a = 0; a < 3; ++a) sh.c[size_t(i)][a] = f32At(buf + 12 * i + 4 * a);
    }
    s->sh.push_back(sh);
  }
  if (f.occl != 0) {
    const uint64_t recsAt = f.occl + 24, planesAt = recsAt + 8 * f.tetCount,
                   blocksAt = planesAt + 8 * f.planeCount;
    for (uint32_t t : s->tetIds) {
      if (!f.read(recsAt + 8ull * t, buf, 8)) return fail(LevelStatus::kCannotOpen, where + "read failed");
      TetOcclusion rec{u32At(buf), u32At(buf + 4)};
      if (rec.kind() == kOcclusionPlanes) {
        if (rec.planeCount() < 1 || rec.offset() + uint64_t(rec.planeCount()) > f.planeCount)
          return bad("occlusion planes out of range");
        for (uint32_t k = 0; k < rec.planeCount(); ++k) {
          if (!f.read(planesAt + 8ull * (rec.offset() + k), buf, 8))
            return fail(LevelStatus::kCannotOpen, where + "read failed");
          OcclusionPlane pl;
          for (int a = 0; a < 4; ++a) pl.c[a] = int16_t(uint16_t(buf[2 * a] | buf[2 * a + 1] << 8));
          s->planes.push_back(pl);
        }
      } else if (rec.kind() == kOcclusionShadowMaps) {
        if (rec.offset() >= f.blockCount) return bad("occlusion shadow map out of range");
        uint8_t block[kShadowMapBlockBytes];
        if (!f.read(blocksAt + uint64_t(kShadowMapBlockBytes) * rec.offset(), block, sizeof block))
          return fail(LevelStatus::kCannotOpen, where + "read failed");
        s->blocks.insert(s->blocks.end(), block, block + sizeof block);
      } else if (rec.kind() != kOcclusionNone) {
        return bad("occlusion kind " + std::to_string(rec.kind()));
      }
      s->occ.push_back(rec);
    }
  }
  loaded_[key] = std::move(s);
  rebuild();
  if (LevelResult v = validateLevel(fine_); !v) {
    loaded_.erase(key);
    rebuild();
    return fail(LevelStatus::kCorrupt, where + v.message);
  }
  return {};
}

void StreamingLevel::unload(const SectorKey& key) {
  if (loaded_.erase(key) > 0) rebuild();
}

void StreamingLevel::rebuild() {
  fineQuery_.reset();
  fine_ = Level{};
  if (loaded_.empty() || !file_) return;
  fine_.content = file_->content;
  fine_.shOrder = file_->shOrder;
  fine_.origin = origin_;
  // The union of the loaded sectors' tets and probes, in file order: local index = rank.
  std::vector<uint32_t> tets, probes;
  for (const auto& [key, s] : loaded_) {
    tets.insert(tets.end(), s->tetIds.begin(), s->tetIds.end());
    probes.insert(probes.end(), s->probeIds.begin(), s->probeIds.end());
  }
  std::sort(tets.begin(), tets.end());
  tets.erase(std::unique(tets.begin(), tets.end()), tets.end());
  std::sort(probes.begin(), probes.end());
  probes.erase(std::unique(probes.begin(), probes.end()), probes.end());
  fine_.probes.resize(probes.size());
  fine_.sh.resize(probes.size());
  fine_.tets.resize(tets.size());
  const bool occluded = file_->occl != 0;
  std::vector<TetOcclusion> occ(occluded ? tets.size() : 0);
  std::vector<const OcclusionPlane*> planeSrc(occ.size(), nullptr);
  std::vector<const uint8_t*> blockSrc(occ.size(), nullptr);
  for (const auto& [key, s] : loaded_) {
    for (size_t k = 0; k < s->probeIds.size(); ++k) {
      const size_t i = indexOf(probes, s->probeIds[k]);
      fine_.probes[i] = s->positions[k];
      fine_.sh[i] = s->sh[k];
    }
    size_t plane = 0, block = 0;
    for (size_t k = 0; k < s->tetIds.size(); ++k) {
      const size_t i = indexOf(tets, s->tetIds[k]);
      Tet t = s->tets[k];
      for (int32_t& v : t.v) v = int32_t(indexOf(probes, uint32_t(v)));
      fine_.tets[i] = t;
      if (occluded) {
        occ[i] = s->occ[k];
        if (s->occ[k].kind() == kOcclusionPlanes) {
          planeSrc[i] = &s->planes[plane];
          plane += s->occ[k].planeCount();
        } else if (s->occ[k].kind() == kOcclusionShadowMaps) {
          blockSrc[i] = &s->blocks[block];
          block += kShadowMapBlockBytes;
        }
      }
    }
  }
  // Neighbours among the loaded tets (a face whose other tet is not loaded is cut: -1). A face of three
  // loaded tets cannot come from a valid file; its tets stay cut rather than walk a wrong link.
  if (!linkTetNeighbours(fine_.tets, fine_.probes.size()).empty())
    for (Tet& t : fine_.tets) t.n[0] = t.n[1] = t.n[2] = t.n[3] = -1;
  // Occlusion, repacked in local tet order (offsets renumbered, the records' other bits kept).
  if (occluded) {
    LevelOcclusion& o = fine_.occlusion;
    o.tets.resize(tets.size());
    for (size_t i = 0; i < tets.size(); ++i) {
      const TetOcclusion rec = occ[i];
      if (rec.kind() == kOcclusionPlanes) {
        o.tets[i] =
            makeTetOcclusion(kOcclusionPlanes, rec.planeCount(), uint32_t(o.planes.size()), rec.cells);
        o.planes.insert(o.planes.end(), planeSrc[i], planeSrc[i] + rec.planeCount());
      } else if (rec.kind() == kOcclusionShadowMaps) {
        o.tets[i] = makeTetOcclusion(kOcclusionShadowMaps, 0,
                                     uint32_t(o.shadowMaps.size() / kShadowMapBlockBytes), rec.cells);
        o.shadowMaps.insert(o.shadowMaps.end(), blockSrc[i], blockSrc[i] + kShadowMapBlockBytes);
      } else {
        o.tets[i] = rec;
      }
    }
  }
  // The loaded cells' BSPs under a hash table of their own (the grid's frame, cellHash, linear probing).
  CellGrid& g = fine_.cellGrid;
  g.min = grid_.min;
  g.cellSize = grid_.cellSize;
  auto remap = [&](int32_t c, int32_t base) {
    if (c >= 0) return c + base;
    if (c == kEmptyLeaf) return c;
    return ~int32_t(indexOf(tets, uint32_t(~c)));
  };
  std::vector<std::pair<SectorKey, int32_t>> roots;
  for (const auto& [key, s] : loaded_) {
    const auto base = int32_t(g.nodes.size());
    roots.emplace_back(key, remap(s->root, base));
    for (BspNode n : s->nodes) {
      n.child[0] = remap(n.child[0], base);
      n.child[1] = remap(n.child[1], base);
      g.nodes.push_back(n);
      g.leaves += (n.child[0] < 0) + (n.child[1] < 0);
    }
    g.leaves += s->root < 0;
  }
  for (size_t slots = 2;; slots *= 2) {
    if (slots < 2 * roots.size()) continue;
    g.slots.assign(slots, CellSlot{{INT32_MIN, 0, 0}, 0});
    uint32_t longest = 0;
    for (const auto& [key, root] : roots) {
      const int32_t k[3] = {key.x, key.y, key.z};
      size_t h = cellGridSlot(g, k);
      uint32_t probe = 1;
      while (g.slots[h].key[0] != INT32_MIN) h = (h + 1) & (slots - 1), ++probe;
      g.slots[h] = CellSlot{{key.x, key.y, key.z}, root};
      longest = std::max(longest, probe);
    }
    g.maxProbe = longest;
    if (longest <= kMaxCellProbe) break;
  }
  fineQuery_ = std::make_unique<ProbeQuery>(fine_, grid_.cellSize, 1);
}

// Inside a loaded tet: the walk ends in a tet, not in the outer cells (outside the loaded tets' hull, which
// is also where the full level's own hull may be, and whose outer cells the loaded part does not have).
bool StreamingLevel::answersFromLoaded(const glm::dvec3& world) const {
  if (!fineQuery_ || !isLoaded(sectorOf(world))) return false;
  const Location loc = fineQuery_->locate(world);
  return loc.tet >= 0 && loc.outerCell < 0;
}

glm::vec3 StreamingLevel::query(const glm::dvec3& world, const glm::vec3& normal) const {
  if (answersFromLoaded(world)) return fineQuery_->irradiance(world, normal);
  return coarseQuery_ ? coarseQuery_->irradiance(world, normal) : glm::vec3(0.0f);
}

size_t StreamingLevel::bytesInUse() const {
  size_t n = index_.size() + levelBytes(coarse_) + (coarseQuery_ ? queryBytes(*coarseQuery_) : 0);
  for (const auto& [key, s] : loaded_) n += s->bytes();
  return n + levelBytes(fine_) + (fineQuery_ ? queryBytes(*fineQuery_) : 0);
}

}  // namespace tetraprobe
