// Streaming a level by sector (streaming.h, docs/streaming.md): open checks the header and table (the
// parser loadLevel uses, level_file.h) and reads the STRM index and the coarse probe set under the index's
// CRC; load reads one sector's records (tets, their probes and SH, occlusion, the cell's BSP) with seeks
// into the level's own sections and checks them against the sector's CRC (stream_format.h); the loaded
// sectors are joined into one small
// Level (indices renumbered, neighbours outside it cut to -1, the loaded cells' BSPs under a new hash table)
// and queried by an ordinary ProbeQuery. Where a point's cell is loaded and the point lies in a tet, that
// tet, the cell's BSP leaf's tet, the neighbours the walk steps to, their probes and occlusion are all
// loaded (their bounding boxes touch the cell), so the query runs the same operations on the same numbers
// as on the full level. Outside every tet the full level answers from its outer cells, which a loaded part
// does not hold: the coarse set answers there.
#include "tetraprobe/runtime/streaming.h"

#include "tetraprobe/runtime/level_file.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/runtime/tet_adjacency.h"

#include <algorithm>
#include <bit>
#include <climits>
#include <cmath>
#include <cstring>

#include "byte_order.h"
#include "stream_format.h"

namespace tetraprobe {

namespace {

using runtime_detail::StreamHeader;
using runtime_detail::StreamSector;

using runtime_detail::f32At;
using runtime_detail::i32At;
using runtime_detail::u32At;

uint32_t uintAt(const uint8_t* p, uint64_t bytes) {  // little-endian, 1..4 bytes
  uint32_t v = 0;
  for (uint64_t b = 0; b < bytes; ++b) v |= uint32_t(p[b]) << (8 * b);
  return v;
}

LevelResult fail(LevelStatus s, std::string message) {
  return LevelResult{s, std::move(message)};
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

// The open file, where its sectors' records are, and the index's header.
struct StreamingLevel::File {
  runtime_detail::FileSource in;
  runtime_detail::StreamRecords records;
  StreamHeader header;
  uint32_t content = 0, shOrder = 2;
};

size_t SectorRecords::bytes() const {
  return (tetIds.size() + probeIds.size()) * 4 + tets.size() * sizeof(Tet) +
         positions.size() * sizeof(glm::vec3) + sh.size() * sizeof(ShRgb) +
         occ.size() * sizeof(TetOcclusion) + planes.size() * sizeof(OcclusionPlane) + blocks.size() +
         nodes.size() * sizeof(BspNode);
}

StreamingLevel::StreamingLevel() = default;
StreamingLevel::~StreamingLevel() = default;

void StreamingLevel::close() {
  file_.reset();
  openBytesRead_ = 0;
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
  LevelResult r = openChecked(path);
  if (!r) close();
  return r;
}

LevelResult StreamingLevel::openChecked(const std::string& path) {
  path_ = path;
  const std::string name = path + ": ";
  auto f = std::make_unique<File>();
  if (!f->in.open(path)) return fail(LevelStatus::kCannotOpen, name + "cannot open");
  const uint64_t size = f->in.size();
  const auto readFailed = [&] { return fail(LevelStatus::kCannotOpen, name + "read failed"); };
  // The header and the table, checked as loadLevel checks them (level_file.h), then the sections' sizes.
  LevelFileLayout layout;
  uint8_t h[kLevelHeaderBytes];
  if (!f->in.read(0, h, size_t(std::min<uint64_t>(size, kLevelHeaderBytes)))) return readFailed();
  if (LevelResult r = parseLevelHeader(h, size, path, layout); !r) return r;
  std::vector<uint8_t> table(size_t(layout.tableEnd - kLevelHeaderBytes));
  if (!f->in.read(kLevelHeaderBytes, table.data(), table.size())) return readFailed();
  if (LevelResult r = parseLevelTable(table.data(), size, path, layout); !r) return r;
  if (LevelResult r = checkLevelSections(layout, path); !r) return r;
  // The records the sectors read (and the occlusion section's header), then the index: its header, the
  // sector records and the coarse set, checked by the index's CRC. The rest of the file is not read: each
  // sector's bytes are checked by their own CRC when the sector is loaded.
  if (std::string e = runtime_detail::locateStreamRecords(layout, f->in, f->records); !e.empty())
    return fail(LevelStatus::kCorrupt, name + e);
  const runtime_detail::StreamRecords& rec = f->records;
  StreamHeader& x = f->header;
  uint8_t xh[runtime_detail::kStreamHeaderBytes];
  if (rec.strmBytes < sizeof xh)
    return fail(LevelStatus::kCorrupt, name + "streaming index shorter than its header");
  if (!f->in.read(rec.strm, xh, sizeof xh)) return readFailed();
  if (std::string e = runtime_detail::parseStreamHeader(xh, rec.strmBytes, x); !e.empty())
    return fail(LevelStatus::kCorrupt, name + e);
  index_.assign(size_t(x.sectorsBytes()), 0);
  std::vector<uint8_t> coarseBytes(size_t(x.coarseBytes()));
  if (!f->in.read(rec.strm + runtime_detail::kStreamHeaderBytes, index_.data(), index_.size()) ||
      !f->in.read(rec.strm + x.coarseAt(), coarseBytes.data(), coarseBytes.size()))
    return readFailed();
  if (runtime_detail::streamIndexCrc(xh, index_.data(), x, coarseBytes.data()) != x.crc)
    return fail(LevelStatus::kCorrupt, name + "streaming index checksum mismatch");
  grid_.min = x.min;
  grid_.cellSize = x.cellSize;
  origin_ = layout.origin;
  f->content = layout.content;
  f->shOrder = layout.shOrder;
  for (uint32_t s = 0; s < x.sectors; ++s) {
    const StreamSector r =
        runtime_detail::parseStreamSector(index_.data() + runtime_detail::kStreamSectorBytes * s);
    StreamSector previous;
    if (s > 0)
      previous =
          runtime_detail::parseStreamSector(index_.data() + runtime_detail::kStreamSectorBytes * (s - 1));
    if (std::string e = runtime_detail::checkStreamSector(r, s > 0 ? &previous : nullptr, x); !e.empty())
      return fail(LevelStatus::kCorrupt, name + "streaming sector " + std::to_string(s) + ": " + e);
    keys_.push_back(SectorKey{r.key[0], r.key[1], r.key[2]});
  }

  // The coarse set: a level of its own (no occlusion, no grid: its query builds one).
  coarse_.content = f->content;
  coarse_.shOrder = f->shOrder;
  coarse_.origin = origin_;
  const uint8_t* c = coarseBytes.data();
  coarse_.probes.resize(size_t(x.coarseProbes));
  coarse_.sh.resize(size_t(x.coarseProbes));
  coarse_.tets.resize(size_t(x.coarseTets));
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
  openBytesRead_ = f->in.bytesRead();
  file_ = std::move(f);
  return {};
}

SectorKey StreamingLevel::sectorOf(const glm::dvec3& world) const {
  int32_t key[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
  cellGridKey(grid_, world - origin_, key);
  return SectorKey{key[0], key[1], key[2]};
}

bool StreamingLevel::hasOcclusion() const {
  return file_ && file_->records.occl != 0;
}

bool StreamingLevel::hasSector(const SectorKey& key) const {
  return std::binary_search(keys_.begin(), keys_.end(), key);
}

LevelResult StreamingLevel::load(const SectorKey& key) {
  if (!file_) return fail(LevelStatus::kCannotOpen, "streaming level not open");
  if (isLoaded(key)) return {};
  auto s = std::make_unique<Sector>();
  if (LevelResult r = readSector(key, *s); !r) return r;
  loaded_[key] = std::move(s);
  if (std::string e = rebuild(); !e.empty()) {
    loaded_.erase(key);
    rebuild();  // the others, as they were
    return fail(LevelStatus::kCorrupt, path_ + ": sector (" + std::to_string(key.x) + ", " +
                                           std::to_string(key.y) + ", " + std::to_string(key.z) + "): " + e);
  }
  return {};
}

LevelResult StreamingLevel::readSector(const SectorKey& key, SectorRecords& out) {
  out = SectorRecords{};
  if (!file_) return fail(LevelStatus::kCannotOpen, "streaming level not open");
  const auto it = std::lower_bound(keys_.begin(), keys_.end(), key);
  const std::string where = path_ + ": sector (" + std::to_string(key.x) + ", " + std::to_string(key.y) +
                            ", " + std::to_string(key.z) + "): ";
  if (it == keys_.end() || !(*it == key)) return fail(LevelStatus::kCorrupt, where + "not in the index");
  const StreamSector r = runtime_detail::parseStreamSector(
      index_.data() + runtime_detail::kStreamSectorBytes * size_t(it - keys_.begin()));
  File& f = *file_;
  const runtime_detail::StreamRecords& rec = f.records;
  auto bad = [&](const std::string& why) {
    out = SectorRecords{};
    return fail(LevelStatus::kCorrupt, where + why);
  };
  // The sector's bytes (its references and nodes from the index, its records from the level's sections),
  // checked by the sector's CRC before any is decoded.
  runtime_detail::SectorBytes b;
  if (std::string e = runtime_detail::readSectorBytes(f.in, rec, f.header, r, b); !e.empty()) return bad(e);
  if (b.crc != r.crc) return bad("checksum mismatch");
  SectorRecords* s = &out;
  s->tetIds = std::move(b.tetIds);
  s->probeIds = std::move(b.probeIds);
  // Nodes: children >= 0 are later nodes of this sector, leaves name tets of this sector.
  auto validChild = [&](int32_t c, int64_t parent) {
    if (c >= 0) return int64_t(c) > parent && int64_t(c) < int64_t(r.nodeCount);
    return c == kEmptyLeaf || std::binary_search(s->tetIds.begin(), s->tetIds.end(), uint32_t(~c));
  };
  if (!validChild(r.root, -1)) return bad("BSP root out of range");
  s->root = r.root;
  s->nodes.resize(r.nodeCount);
  for (uint32_t k = 0; k < r.nodeCount; ++k) {
    const uint8_t* p = b.nodes.data() + runtime_detail::kStreamNodeBytes * k;
    BspNode& n = s->nodes[k];
    for (int a = 0; a < 4; ++a) n.plane[a] = f32At(p + 4 * a);
    n.child[0] = i32At(p + 16);
    n.child[1] = i32At(p + 20);
    if (!validChild(n.child[0], k) || !validChild(n.child[1], k)) return bad("BSP child out of range");
  }
  const uint64_t indexBytes = rec.tetIndexBytes;
  for (size_t k = 0; k < s->tetIds.size(); ++k) {
    const uint8_t* p = b.tets.data() + 4 * indexBytes * k;
    Tet t;  // neighbours: linked among the loaded tets when the fine level is assembled
    for (int i = 0; i < 4; ++i)
      t.v[i] = int32_t(uintAt(p + indexBytes * uint64_t(i), indexBytes)), t.n[i] = -1;
    for (int i = 0; i < 4; ++i) {
      const int32_t v = t.v[i];
      if (v < 0 || !std::binary_search(s->probeIds.begin(), s->probeIds.end(), uint32_t(v)))
        return bad("tet " + std::to_string(s->tetIds[k]) + " names a probe outside the sector");
      for (int j = 0; j < i; ++j)
        if (t.v[j] == v)
          return bad("tet " + std::to_string(s->tetIds[k]) + " repeats probe " + std::to_string(v));
    }
    s->tets.push_back(t);
  }
  for (size_t k = 0; k < s->probeIds.size(); ++k) {
    const uint8_t* p = b.positions.data() + 12 * k;
    s->positions.emplace_back(f32At(p), f32At(p + 4), f32At(p + 8));
    const uint8_t* q = b.sh.data() + rec.shRecord * k;
    ShRgb sh;
    if (rec.shRecord == sizeof(ShHalf)) {
      ShHalf h;
      for (int i = 0; i < 28; ++i) h.h[i] = uint16_t(q[2 * i] | q[2 * i + 1] << 8);
      bool valid = true;
      sh = decodeShHalf(h, &valid);
      if (!valid)
        return bad("probe " + std::to_string(s->probeIds[k]) + ": SH record is not valid half precision");
    } else {
      for (int i = 0; i < kShCoeffCount; ++i)
        for (int a = 0; a < 3; ++a) sh.c[size_t(i)][a] = f32At(q + 12 * i + 4 * a);
    }
    s->sh.push_back(sh);
  }
  if (rec.occl != 0) {  // readSectorBytes checked the kinds and the plane and block ranges
    for (size_t k = 0; k < s->tetIds.size(); ++k)
      s->occ.push_back(TetOcclusion{u32At(b.occ.data() + 8 * k), u32At(b.occ.data() + 8 * k + 4)});
    for (size_t k = 0; k < b.planes.size(); k += 8) {
      OcclusionPlane pl;
      for (int a = 0; a < 4; ++a)
        pl.c[a] = int16_t(uint16_t(b.planes[k + 2 * a] | b.planes[k + 2 * a + 1] << 8));
      s->planes.push_back(pl);
    }
    s->blocks = std::move(b.blocks);
  }
  return {};
}

void StreamingLevel::unload(const SectorKey& key) {
  if (loaded_.erase(key) > 0) rebuild();  // the others were linked before: no error
}

std::string StreamingLevel::rebuild() {
  fineQuery_.reset();
  fine_ = Level{};
  if (loaded_.empty() || !file_) return {};
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
  const bool occluded = file_->records.occl != 0;
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
  // loaded tets cannot come from a valid file (loadLevel refuses it): the load that made it is refused.
  if (std::string e = linkTetNeighbours(fine_.tets, fine_.probes.size()); !e.empty()) {
    fine_ = Level{};
    return e;
  }
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
  // Checked before a query is built on it: indices, numbers, occlusion (the checks loadLevel makes).
  if (LevelResult v = validateLevel(fine_); !v) {
    fine_ = Level{};
    return v.message;
  }
  fineQuery_ = std::make_unique<ProbeQuery>(fine_, grid_.cellSize, 1);
  return {};
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
  size_t n = (file_ ? size_t(runtime_detail::kStreamHeaderBytes) : 0) + index_.size() + levelBytes(coarse_) +
             (coarseQuery_ ? queryBytes(*coarseQuery_) : 0);
  for (const auto& [key, s] : loaded_) n += s->bytes();
  return n + levelBytes(fine_) + (fineQuery_ ? queryBytes(*fineQuery_) : 0);
}

}  // namespace tetraprobe
