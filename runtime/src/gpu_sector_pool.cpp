// GPU streaming by sector: a streamed level's sectors written into and evicted from fixed-size slots of the
// lookup's six buffers. Contract and layout: runtime/include/tetraprobe/runtime/gpu_sector_pool.h.
#include "tetraprobe/runtime/gpu_sector_pool.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <set>
#include <utility>

#include "tetraprobe/runtime/face_blend.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/runtime/shade.h"
#include "tetraprobe/runtime/start_bricks.h"

namespace tetraprobe {
namespace {

// A plane tet's block: its `cells` word, then up to three planes of two uints (gpu_layout.h).
constexpr uint32_t kPlaneBlockUints = 1 + 2 * 3;
constexpr uint32_t kShadowBlockUints = kShadowMapBlockBytes / 4;

uint64_t pad64(uint64_t bytes) {
  return std::max<uint64_t>(64, (bytes + 63) / 64 * 64);
}

template <class T>
void put(std::vector<char>& buffer, uint64_t offset, const T& value) {
  std::memcpy(buffer.data() + offset, &value, sizeof value);
}

// Per kind, the sum of the n largest counts.
uint32_t sumLargest(std::vector<uint32_t> counts, uint32_t n) {
  std::sort(counts.begin(), counts.end(), std::greater<>());
  uint64_t sum = 0;
  for (size_t i = 0; i < counts.size() && i < n; ++i) sum += counts[i];
  return uint32_t(std::min<uint64_t>(sum, INT32_MAX));
}

struct Layout {
  uint64_t tetBytes, probeBytes, gridBytes, outerBytes, cellBytes, occBytes;
  uint64_t tetRecords, shOffset, occHeaders, occPlanes, occShadows, cellSlots, cellBricks;
  size_t tableSlots;
  GpuTetPacking packing;
};

Layout layoutFor(const GpuPoolCapacity& cap, size_t coarseTets, size_t coarseProbes, size_t gridCells,
                 size_t outerCells, bool occlusion) {
  Layout l{};
  const uint64_t tets = coarseTets + uint64_t(cap.tets), probes = coarseProbes + uint64_t(cap.probes);
  l.packing = gpuTetPacking(size_t(probes), size_t(tets));
  l.tetRecords = sizeof(GpuTetHeader);
  l.tetBytes = pad64(l.tetRecords + 4 * (tets * l.packing.strideUints + kGpuTetTailUints));
  l.shOffset = 4 * kGpuPositionFloatsPerProbe * probes;
  l.probeBytes = pad64(l.shOffset + 4 * kGpuShUintsPerProbe * probes);
  l.gridBytes = pad64(kGpuGridStartTetOffset + 4 * gridCells);
  l.outerBytes = pad64(kGpuOuterCellsOffset + sizeof(GpuOuterCell) * outerCells);
  l.tableSlots = 2;
  while (l.tableSlots < 2 * size_t(std::max<uint32_t>(cap.sectors, 1))) l.tableSlots *= 2;
  l.cellSlots = sizeof(GpuCellGridHeader);
  l.cellBricks = l.cellSlots + sizeof(CellSlot) * l.tableSlots;
  const uint64_t entries = uint64_t(cap.sectors) * kStartBrickDim * kStartBrickDim * kStartBrickDim;
  l.cellBytes = pad64(l.cellBricks + 4 * packedFieldWords(entries, l.packing.neighbourBits));
  l.occHeaders = sizeof(GpuOcclusionHeader);
  if (occlusion) {
    l.occPlanes = l.occHeaders + 4 * tets;
    l.occShadows = l.occPlanes + 4 * uint64_t(kPlaneBlockUints) * cap.planeTets;
    l.occBytes = pad64(l.occShadows + 4 * uint64_t(kShadowBlockUints) * cap.shadowTets);
  } else {
    l.occPlanes = l.occShadows = l.occHeaders;
    l.occBytes = pad64(l.occHeaders);
  }
  return l;
}

}  // namespace

bool measureSectors(StreamingLevel& level, std::vector<GpuSectorSizes>& out, std::string* error) {
  out.clear();
  SectorRecords r;
  for (const SectorKey& key : level.sectors()) {
    if (LevelResult res = level.readSector(key, r); !res) {
      if (error) *error = res.message;
      out.clear();
      return false;
    }
    GpuSectorSizes s;
    s.key = key;
    s.tets = uint32_t(r.tetIds.size());
    s.probes = uint32_t(r.probeIds.size());
    for (const TetOcclusion& o : r.occ) {
      s.planeTets += o.kind() == kOcclusionPlanes;
      s.shadowTets += o.kind() == kOcclusionShadowMaps;
    }
    out.push_back(s);
  }
  return true;
}

GpuPoolCapacity gpuPoolCapacityFor(const std::vector<GpuSectorSizes>& sizes, uint32_t sectors) {
  std::vector<uint32_t> tets, probes, planes, shadows;
  for (const GpuSectorSizes& s : sizes) {
    tets.push_back(s.tets);
    probes.push_back(s.probes);
    planes.push_back(s.planeTets);
    shadows.push_back(s.shadowTets);
  }
  GpuPoolCapacity c;
  c.sectors = uint32_t(std::min<size_t>(sectors, sizes.size()));
  c.tets = sumLargest(tets, sectors);
  c.probes = sumLargest(probes, sectors);
  c.planeTets = sumLargest(planes, sectors);
  c.shadowTets = sumLargest(shadows, sectors);
  return c;
}

size_t gpuPoolBytes(const StreamingLevel& level, const GpuPoolCapacity& capacity) {
  // The coarse set's start grid and outer cells, as the full level's upload takes them from its ProbeQuery.
  const ProbeQuery& q = level.coarseQuery();
  const Layout l = layoutFor(capacity, level.coarse().tets.size(), level.coarse().probes.size(),
                             q.startGrid().startTet.size(), q.outerCells().size(), level.hasOcclusion());
  return size_t(l.tetBytes + l.probeBytes + l.gridBytes + l.outerBytes + l.cellBytes + l.occBytes);
}

std::string GpuSectorPool::init(StreamingLevel& level, const GpuPoolCapacity& capacity,
                                int32_t maxWalkSteps) {
  *this = GpuSectorPool{};
  if (level.sectors().empty() || level.coarse().tets.empty()) return "streaming level not open";
  const Level& coarse = level.coarse();
  const StartGrid& coarseGrid = level.coarseQuery().startGrid();
  const std::vector<OuterCell>& coarseOuter = level.coarseQuery().outerCells();
  occlusion_ = level.hasOcclusion();
  const Layout l = layoutFor(capacity, coarse.tets.size(), coarse.probes.size(), coarseGrid.startTet.size(),
                             coarseOuter.size(), occlusion_);
  const uint64_t tets = coarse.tets.size() + uint64_t(capacity.tets);
  const uint64_t probes = coarse.probes.size() + uint64_t(capacity.probes);
  if (tets >= (uint64_t(1) << 31) || probes >= (uint64_t(1) << 31))
    return "pool capacity beyond 2^31 tets or probes";
  if (occlusion_ && (uint64_t(capacity.planeTets) * kPlaneBlockUints > kGpuOccMaxOffset ||
                     capacity.shadowTets > kGpuOccMaxOffset))
    return "pool's occlusion slots beyond the GPU record's 2^24 offsets";
  level_ = &level;
  cap_ = capacity;
  packing_ = l.packing;
  coarseTets_ = uint32_t(coarse.tets.size());
  coarseProbes_ = uint32_t(coarse.probes.size());
  tetRecords_ = l.tetRecords;
  shOffset_ = l.shOffset;
  occHeaders_ = l.occHeaders;
  occPlanes_ = l.occPlanes;
  occShadows_ = l.occShadows;
  cellSlots_ = l.cellSlots;
  cellBricks_ = l.cellBricks;
  tableSlots_ = l.tableSlots;
  grid_ = level.sectorGrid();

  variant_.shOrder = coarse.shOrder == 1 ? 1u : 2u;
  variant_.planes = variant_.shadowMaps = occlusion_;
  variant_.outerCells = !coarseOuter.empty();
  variant_.cellGrid = true;
  variant_.tetVertexBits = packing_.vertexBits;
  variant_.tetNeighbourBits = packing_.neighbourBits;
  variant_.tetStride = packing_.strideUints;

  std::vector<char>* b = buffers_.bytes;
  b[kGpuBindingTets].assign(size_t(l.tetBytes), 0);
  b[kGpuBindingProbes].assign(size_t(l.probeBytes), 0);
  b[kGpuBindingGrid].assign(size_t(l.gridBytes), 0);
  b[kGpuBindingOuterCells].assign(size_t(l.outerBytes), 0);
  b[kGpuBindingCells].assign(size_t(l.cellBytes), 0);
  b[kGpuBindingOcclusion].assign(size_t(l.occBytes), 0);

  // The CPU copy: every slot exists; free ones hold a tet of probe 0 with no neighbours.
  pool_.shOrder = coarse.shOrder;
  pool_.content = coarse.content;
  pool_.origin = coarse.origin;
  pool_.probes.assign(size_t(probes), glm::vec3(0.0f));
  pool_.sh.assign(size_t(probes), ShRgb{});
  pool_.tets.assign(size_t(tets), Tet{{0, 0, 0, 0}, {-1, -1, -1, -1}});
  if (occlusion_) {
    pool_.occlusion.tets.assign(size_t(tets), TetOcclusion{});
    pool_.occlusion.planes.assign(size_t(capacity.planeTets) * 3, OcclusionPlane{});
    pool_.occlusion.shadowMaps.assign(size_t(capacity.shadowTets) * kShadowMapBlockBytes, kShadowMapNoHit);
  }
  probeGlobal_.assign(size_t(probes), 0);
  tetRefs_.assign(size_t(tets), 0);
  probeRefs_.assign(size_t(probes), 0);
  occSlot_.assign(size_t(tets), -1);
  // Free lists popped from the back: lowest slots first.
  for (int64_t s = int64_t(tets) - 1; s >= int64_t(coarseTets_); --s) freeTets_.push_back(int32_t(s));
  for (int64_t s = int64_t(probes) - 1; s >= int64_t(coarseProbes_); --s) freeProbes_.push_back(int32_t(s));
  for (int64_t s = int64_t(capacity.planeTets) - 1; s >= 0; --s) freePlanes_.push_back(int32_t(s));
  for (int64_t s = int64_t(capacity.shadowTets) - 1; s >= 0; --s) freeShadows_.push_back(int32_t(s));
  for (int64_t s = int64_t(capacity.sectors) - 1; s >= 0; --s) freeBricks_.push_back(int32_t(s));

  // Headers.
  GpuTetHeader th{};
  th.vertexBits = packing_.vertexBits;
  th.neighbourBits = packing_.neighbourBits;
  th.strideUints = packing_.strideUints;
  th.count = uint32_t(tets);
  put(b[kGpuBindingTets], 0, th);
  GpuGridHeader gh{};
  for (int a = 0; a < 3; ++a) {
    gh.min[a] = coarseGrid.min[a];
    gh.cellSize[a] = coarseGrid.cellSize[a];
    gh.dims[a] = coarseGrid.dims[a];
  }
  gh.tetCount = int32_t(tets);
  gh.probeCount = int32_t(probes);
  gh.maxWalkSteps = maxWalkSteps;
  put(b[kGpuBindingGrid], 0, gh);
  std::memcpy(b[kGpuBindingGrid].data() + kGpuGridStartTetOffset, coarseGrid.startTet.data(),
              4 * coarseGrid.startTet.size());
  GpuOuterHeader oh{};
  oh.count = int32_t(coarseOuter.size());
  put(b[kGpuBindingOuterCells], 0, oh);
  for (size_t k = 0; k < coarseOuter.size(); ++k)
    put(b[kGpuBindingOuterCells], kGpuOuterCellsOffset + sizeof(GpuOuterCell) * k,
        gpuOuterCell(coarseOuter[k]));
  GpuCellGridHeader ch{};
  for (int a = 0; a < 3; ++a) ch.min[a] = grid_.min[a];
  ch.cellSize = grid_.cellSize;
  ch.slotMask = uint32_t(tableSlots_ - 1);
  ch.maxProbe = uint32_t(tableSlots_);  // the search stops at an empty slot first (the table is half empty)
  ch.brickOffset = int32_t(4 * tableSlots_);
  ch.brickDim = kStartBrickDim;
  put(b[kGpuBindingCells], 0, ch);
  table_.assign(tableSlots_, CellSlot{{INT32_MIN, 0, 0}, 0});
  brickStarts_.assign(size_t(capacity.sectors) * kStartBrickDim * kStartBrickDim * kStartBrickDim, 0);
  for (size_t h = 0; h < tableSlots_; ++h) writeCellSlot(h);
  GpuOcclusionHeader och{};
  if (occlusion_) {
    och.tetCount = uint32_t(tets);
    och.planeOffset = uint32_t((occPlanes_ - occHeaders_) / 4);
    och.shadowOffset = uint32_t((occShadows_ - occHeaders_) / 4);
  }
  put(b[kGpuBindingOcclusion], 0, och);

  // The coarse set: its own indices are its slots.
  for (uint32_t p = 0; p < coarseProbes_; ++p) {
    pool_.probes[p] = coarse.probes[p];
    pool_.sh[p] = coarse.sh[p];
    probeRefs_[p] = 1;
    ShHalf h;
    if (!encodeShHalf(coarse.sh[p], &h)) {
      *this = GpuSectorPool{};
      return "coarse probe " + std::to_string(p) + " has an SH coefficient the GPU record cannot hold";
    }
    writeProbe(int32_t(p));
  }
  for (uint32_t t = 0; t < coarseTets_; ++t) {
    pool_.tets[t] = coarse.tets[t];
    tetRefs_[t] = 1;
    writeTet(int32_t(t));
    if (occlusion_) writeOcclusionHeader(int32_t(t));
  }
  dirty_.clear();
  for (uint32_t i = 0; i < kGpuBindingCount; ++i) markDirty(i, 0, b[i].size());
  return {};
}

void GpuSectorPool::markDirty(uint32_t binding, uint64_t offset, uint64_t bytes) {
  if (bytes > 0) dirty_.push_back(GpuBufferRange{binding, offset, bytes});
}

std::vector<GpuBufferRange> GpuSectorPool::takeDirtyRanges() {
  std::sort(dirty_.begin(), dirty_.end(), [](const GpuBufferRange& a, const GpuBufferRange& b) {
    return a.binding != b.binding ? a.binding < b.binding : a.offset < b.offset;
  });
  // Merged where they overlap or lie within 64 bytes of each other (one copy region instead of many).
  std::vector<GpuBufferRange> out;
  for (const GpuBufferRange& r : dirty_) {
    if (!out.empty() && out.back().binding == r.binding &&
        r.offset <= out.back().offset + out.back().bytes + 64)
      out.back().bytes = std::max(out.back().bytes, r.offset + r.bytes - out.back().offset);
    else
      out.push_back(r);
  }
  dirty_.clear();
  return out;
}

size_t GpuSectorPool::bytes() const {
  size_t n = 0;
  for (const std::vector<char>& b : buffers_.bytes) n += b.size();
  return n;
}

size_t GpuSectorPool::bytesInUse() const {
  if (!level_) return 0;
  // Headers, the coarse start grid and outer cells and the cells' hash table, then the slots in use.
  size_t n = buffers_.bytes[kGpuBindingGrid].size() + buffers_.bytes[kGpuBindingOuterCells].size() +
             tetRecords_ + size_t(cellBricks_) + size_t(occHeaders_);
  const size_t tets = pool_.tets.size() - freeTets_.size(), probes = pool_.probes.size() - freeProbes_.size();
  n += tets * (4 * packing_.strideUints + (occlusion_ ? 4 : 0));
  n += probes * 4 * (kGpuPositionFloatsPerProbe + kGpuShUintsPerProbe);
  n += (cap_.planeTets - freePlanes_.size()) * 4 * kPlaneBlockUints;
  n += (cap_.shadowTets - freeShadows_.size()) * 4 * kShadowBlockUints;
  const uint64_t perBrick = uint64_t(kStartBrickDim) * kStartBrickDim * kStartBrickDim;
  n += size_t((cap_.sectors - freeBricks_.size()) * perBrick * packing_.neighbourBits / 8);
  return n;
}

void GpuSectorPool::writeTet(int32_t slot) {
  uint32_t record[8] = {};
  packGpuTet(pool_.tets[size_t(slot)], packing_, record);
  const uint64_t at = tetRecords_ + 4 * uint64_t(packing_.strideUints) * uint64_t(slot);
  std::memcpy(buffers_.bytes[kGpuBindingTets].data() + at, record, 4 * packing_.strideUints);
  markDirty(kGpuBindingTets, at, 4 * packing_.strideUints);
}

void GpuSectorPool::writeOcclusionHeader(int32_t slot) {
  const TetOcclusion& rec = pool_.occlusion.tets[size_t(slot)];
  uint32_t offset = 0;
  if (rec.kind() == kOcclusionPlanes) offset = uint32_t(occSlot_[size_t(slot)]) * kPlaneBlockUints;
  if (rec.kind() == kOcclusionShadowMaps) offset = uint32_t(occSlot_[size_t(slot)]);
  const uint32_t word = gpuOcclusionHeader(rec, faceBlendMask(pool_, pool_.occlusion, slot), offset);
  const uint64_t at = occHeaders_ + 4 * uint64_t(slot);
  put(buffers_.bytes[kGpuBindingOcclusion], at, word);
  markDirty(kGpuBindingOcclusion, at, 4);
}

void GpuSectorPool::writeProbe(int32_t slot) {
  std::vector<char>& b = buffers_.bytes[kGpuBindingProbes];
  const uint64_t at = 4 * kGpuPositionFloatsPerProbe * uint64_t(slot);
  std::memcpy(b.data() + at, &pool_.probes[size_t(slot)], 12);
  markDirty(kGpuBindingProbes, at, 12);
  ShHalf h;
  encodeShHalf(pool_.sh[size_t(slot)], &h);  // checked when the sector was read (a valid half record)
  const uint64_t sh = shOffset_ + 4 * kGpuShUintsPerProbe * uint64_t(slot);
  std::memcpy(b.data() + sh, &h, sizeof h);
  markDirty(kGpuBindingProbes, sh, sizeof h);
}

void GpuSectorPool::writeBrick(int32_t brick, const std::vector<int32_t>& startTets) {
  std::vector<char>& b = buffers_.bytes[kGpuBindingCells];
  const uint32_t bits = packing_.neighbourBits;
  const uint64_t perBrick = uint64_t(kStartBrickDim) * kStartBrickDim * kStartBrickDim;
  const uint64_t firstBit = uint64_t(brick) * perBrick * bits, lastBit = firstBit + perBrick * bits;
  auto* words = reinterpret_cast<uint32_t*>(b.data() + cellBricks_);
  for (uint64_t e = 0; e < perBrick; ++e) putBits(words, firstBit + e * bits, bits, uint32_t(startTets[e]));
  std::copy(startTets.begin(), startTets.end(), brickStarts_.begin() + ptrdiff_t(perBrick * uint64_t(brick)));
  const uint64_t w0 = firstBit / 32, w1 = (lastBit + 31) / 32;
  markDirty(kGpuBindingCells, cellBricks_ + 4 * w0, 4 * (w1 - w0));
}

void GpuSectorPool::writeCellSlot(size_t h) {
  const uint64_t at = cellSlots_ + sizeof(CellSlot) * h;
  put(buffers_.bytes[kGpuBindingCells], at, table_[h]);
  markDirty(kGpuBindingCells, at, sizeof(CellSlot));
}

bool GpuSectorPool::insertCell(const SectorKey& key, int32_t brick) {
  const int32_t k[3] = {key.x, key.y, key.z};
  size_t h = size_t(cellHash(k[0], k[1], k[2])) & (tableSlots_ - 1);
  while (table_[h].key[0] != INT32_MIN) h = (h + 1) & (tableSlots_ - 1);
  table_[h] = CellSlot{{key.x, key.y, key.z}, brick};
  writeCellSlot(h);
  return true;
}

void GpuSectorPool::eraseCell(const SectorKey& key) {
  const size_t mask = tableSlots_ - 1;
  size_t h = size_t(cellHash(key.x, key.y, key.z)) & mask;
  while (table_[h].key[0] != INT32_MIN &&
         !(table_[h].key[0] == key.x && table_[h].key[1] == key.y && table_[h].key[2] == key.z))
    h = (h + 1) & mask;
  if (table_[h].key[0] == INT32_MIN) return;
  // Backward-shift deletion: every later entry of the chain whose home lies cyclically at or before the
  // hole moves into it, so a search still meets every key before an empty slot.
  size_t hole = h;
  for (size_t j = (h + 1) & mask; table_[j].key[0] != INT32_MIN; j = (j + 1) & mask) {
    const size_t home = size_t(cellHash(table_[j].key[0], table_[j].key[1], table_[j].key[2])) & mask;
    if (((j - home) & mask) >= ((j - hole) & mask)) {
      table_[hole] = table_[j];
      writeCellSlot(hole);
      hole = j;
    }
  }
  table_[hole] = CellSlot{{INT32_MIN, 0, 0}, 0};
  writeCellSlot(hole);
}

bool GpuSectorPool::locateLoaded(const glm::dvec3& world, Location& loc) const {
  if (!level_ || sectors_.empty()) return false;
  const glm::dvec3 x = world - pool_.origin;
  int32_t key[3];
  if (!cellGridKey(grid_, x, key)) return false;  // not finite, or beyond the key range
  const size_t mask = tableSlots_ - 1;
  size_t h = size_t(cellHash(key[0], key[1], key[2])) & mask;
  while (table_[h].key[0] != INT32_MIN &&
         !(table_[h].key[0] == key[0] && table_[h].key[1] == key[1] && table_[h].key[2] == key[2]))
    h = (h + 1) & mask;
  if (table_[h].key[0] == INT32_MIN) return false;
  // The sub-cell as the shader finds it (tetraprobeCellStartTet).
  const int dim = kStartBrickDim;
  int s[3];
  for (int a = 0; a < 3; ++a) {
    const double g = (x[a] - double(grid_.min[a])) / double(grid_.cellSize) - double(key[a]);
    s[a] = int(std::clamp(g * double(dim), 0.0, double(dim - 1)));
  }
  const size_t entry =
      size_t(table_[h].root) * size_t(dim * dim * dim) + size_t(s[0] + dim * (s[1] + dim * s[2]));
  return locateByWalk(pool_, x, brickStarts_[entry], loc);
}

bool GpuSectorPool::answersFromLoaded(const glm::dvec3& world) const {
  Location loc;
  return locateLoaded(world, loc);
}

glm::vec3 GpuSectorPool::irradiance(const glm::dvec3& world, const glm::vec3& normal) const {
  Location loc;
  if (locateLoaded(world, loc))
    return shadeLocated(pool_, occlusion_ ? &pool_.occlusion : nullptr, loc, world, normal);
  return level_ ? level_->coarseQuery().irradiance(world, normal) : glm::vec3(0.0f);
}

GpuSectorPool::FaceKey GpuSectorPool::faceKey(int32_t slot, int k) const {
  const Tet& t = pool_.tets[size_t(slot)];
  FaceKey f{};
  int n = 0;
  for (int i = 0; i < 4; ++i)
    if (i != k) f.v[n++] = probeGlobal_[size_t(t.v[i])];
  std::sort(f.v, f.v + 3);
  return f;
}

void GpuSectorPool::linkFaces(int32_t slot) {
  for (int k = 0; k < 4; ++k) {
    const FaceKey f = faceKey(slot, k);
    const auto [it, inserted] = faces_.try_emplace(f, 4 * slot + k);
    if (inserted) continue;
    // The face's other tet: link both ways (a valid level has no face of three tets; the second stays cut).
    const int32_t other = it->second / 4, m = it->second % 4;
    if (pool_.tets[size_t(other)].n[m] >= 0) continue;
    pool_.tets[size_t(slot)].n[k] = other;
    pool_.tets[size_t(other)].n[m] = slot;
    writeTet(other);
  }
  writeTet(slot);
}

void GpuSectorPool::writeStarHeaders(const std::vector<int32_t>& slots) {
  // The probe flags of a tet read its probes' stars (face_blend.h): every tet of the stars around these. A star
  // is walked once: (probe, tet) pairs a complete walk reached are skipped (a resident star may be in pieces,
  // so the pair, not the probe alone, says the piece was walked; a walk cut at kFaceBlendStarTets marks none).
  std::vector<int32_t> touched;
  std::set<std::pair<int32_t, int32_t>> walked;  // (probe, tet)
  for (int32_t s : slots)
    for (int i = 0; i < 4; ++i) {
      const int32_t probe = pool_.tets[size_t(s)].v[i];
      if (walked.count({probe, s})) continue;
      const std::vector<int32_t> star = faceBlendStar(pool_, s, i);
      touched.insert(touched.end(), star.begin(), star.end());
      if (star.size() < size_t(kFaceBlendStarTets))
        for (int32_t t : star) walked.insert({probe, t});
    }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  for (int32_t s : touched) writeOcclusionHeader(s);
}

void GpuSectorPool::unlinkFaces(int32_t slot) {
  Tet& t = pool_.tets[size_t(slot)];
  std::vector<int32_t> former;
  for (int k = 0; k < 4; ++k) {
    const FaceKey f = faceKey(slot, k);
    const auto it = faces_.find(f);
    if (it != faces_.end() && it->second == 4 * slot + k) {
      faces_.erase(it);
      // The other tet (if any) becomes the face's holder.
      if (t.n[k] >= 0) {
        const Tet& o = pool_.tets[size_t(t.n[k])];
        for (int m = 0; m < 4; ++m)
          if (o.n[m] == slot) faces_.emplace(f, 4 * t.n[k] + m);
      }
    }
    if (t.n[k] >= 0) {
      const int32_t other = t.n[k];
      Tet& o = pool_.tets[size_t(other)];
      for (int m = 0; m < 4; ++m)
        if (o.n[m] == slot) o.n[m] = -1;
      writeTet(other);
      former.push_back(other);
      t.n[k] = -1;
    }
  }
  // The former neighbours' stars lost this tet (its data no longer reaches their probe flags).
  if (occlusion_) writeStarHeaders(former);
}

LevelResult GpuSectorPool::load(const SectorKey& key) {
  if (!level_) return LevelResult{LevelStatus::kCannotOpen, "GPU sector pool not initialized"};
  if (isLoaded(key)) return {};
  SectorRecords r;
  if (LevelResult res = level_->readSector(key, r); !res) return res;
  const std::string where = "sector (" + std::to_string(key.x) + ", " + std::to_string(key.y) + ", " +
                            std::to_string(key.z) + "): ";
  if (r.tetIds.empty()) return LevelResult{LevelStatus::kCorrupt, where + "holds no tets"};
  // Room first: nothing is written unless every record fits.
  size_t newTets = 0, newProbes = 0, newPlanes = 0, newShadows = 0;
  for (size_t k = 0; k < r.tetIds.size(); ++k) {
    if (tetSlot_.count(r.tetIds[k])) continue;
    ++newTets;
    if (occlusion_ && k < r.occ.size()) {
      newPlanes += r.occ[k].kind() == kOcclusionPlanes;
      newShadows += r.occ[k].kind() == kOcclusionShadowMaps;
    }
  }
  for (uint32_t p : r.probeIds) newProbes += probeSlot_.count(p) == 0;
  if (freeBricks_.empty() || newTets > freeTets_.size() || newProbes > freeProbes_.size() ||
      newPlanes > freePlanes_.size() || newShadows > freeShadows_.size())
    return LevelResult{LevelStatus::kTooLarge,
                       where + "does not fit in the GPU pool's free slots (" + std::to_string(newTets) +
                           " tets, " + std::to_string(newProbes) + " probes needed; " +
                           std::to_string(freeTets_.size()) + " and " + std::to_string(freeProbes_.size()) +
                           " free, " + std::to_string(freeBricks_.size()) + " bricks)"};
  for (const ShRgb& sh : r.sh) {
    ShHalf h;
    if (!encodeShHalf(sh, &h))
      return LevelResult{LevelStatus::kCorrupt, where + "an SH coefficient the GPU record cannot hold"};
  }

  // Probes.
  for (size_t k = 0; k < r.probeIds.size(); ++k) {
    const uint32_t id = r.probeIds[k];
    auto [it, inserted] = probeSlot_.try_emplace(id, -1);
    if (inserted) {
      it->second = freeProbes_.back();
      freeProbes_.pop_back();
      const auto s = size_t(it->second);
      probeGlobal_[s] = id;
      pool_.probes[s] = r.positions[k];
      pool_.sh[s] = r.sh[k];
      writeProbe(it->second);
    }
    ++probeRefs_[size_t(it->second)];
  }
  // Tets: records and occlusion first (the probe flags read the stars' occlusion), then the links.
  std::vector<int32_t> added;
  size_t plane = 0, block = 0;
  for (size_t k = 0; k < r.tetIds.size(); ++k) {
    const uint32_t id = r.tetIds[k];
    const TetOcclusion rec = occlusion_ && k < r.occ.size() ? r.occ[k] : TetOcclusion{};
    const uint32_t planes = rec.kind() == kOcclusionPlanes ? rec.planeCount() : 0u;
    auto [it, inserted] = tetSlot_.try_emplace(id, -1);
    if (inserted) {
      it->second = freeTets_.back();
      freeTets_.pop_back();
      const auto s = size_t(it->second);
      Tet t = r.tets[k];
      for (int32_t& v : t.v) v = probeSlot_.at(uint32_t(v));
      for (int32_t& n : t.n) n = -1;
      pool_.tets[s] = t;
      if (occlusion_) {
        if (rec.kind() == kOcclusionPlanes) {
          const int32_t p = freePlanes_.back();
          freePlanes_.pop_back();
          occSlot_[s] = p;
          pool_.occlusion.tets[s] = makeTetOcclusion(kOcclusionPlanes, planes, uint32_t(3 * p), rec.cells);
          std::vector<char>& b = buffers_.bytes[kGpuBindingOcclusion];
          const uint64_t at = occPlanes_ + 4 * uint64_t(kPlaneBlockUints) * uint64_t(p);
          put(b, at, rec.cells);
          for (uint32_t q = 0; q < planes; ++q) {
            const OcclusionPlane& pl = r.planes[plane + q];
            pool_.occlusion.planes[size_t(3 * p) + q] = pl;
            put(b, at + 4 + 8 * q, uint32_t(uint16_t(pl.c[0])) | uint32_t(uint16_t(pl.c[1])) << 16);
            put(b, at + 8 + 8 * q, uint32_t(uint16_t(pl.c[2])) | uint32_t(uint16_t(pl.c[3])) << 16);
          }
          markDirty(kGpuBindingOcclusion, at, 4 * (1 + 2 * uint64_t(planes)));
        } else if (rec.kind() == kOcclusionShadowMaps) {
          const int32_t m = freeShadows_.back();
          freeShadows_.pop_back();
          occSlot_[s] = m;
          pool_.occlusion.tets[s] = makeTetOcclusion(kOcclusionShadowMaps, 0, uint32_t(m), rec.cells);
          std::memcpy(pool_.occlusion.shadowMaps.data() + size_t(m) * kShadowMapBlockBytes,
                      r.blocks.data() + block, kShadowMapBlockBytes);
          const uint64_t at = occShadows_ + uint64_t(kShadowMapBlockBytes) * uint64_t(m);
          std::memcpy(buffers_.bytes[kGpuBindingOcclusion].data() + at, r.blocks.data() + block,
                      kShadowMapBlockBytes);
          markDirty(kGpuBindingOcclusion, at, kShadowMapBlockBytes);
        } else {
          occSlot_[s] = -1;
          pool_.occlusion.tets[s] = rec;
        }
      }
      added.push_back(it->second);
    }
    plane += planes;
    block += rec.kind() == kOcclusionShadowMaps ? size_t(kShadowMapBlockBytes) : 0;
    ++tetRefs_[size_t(it->second)];
  }
  for (int32_t s : added) linkFaces(s);
  if (occlusion_) writeStarHeaders(added);

  // The start brick: each sub-cell's centre descends the cell's BSP to its leaf tet, then walks toward the
  // centre over the resident tets as buildStartBricks does; an empty leaf takes the previous entry's start.
  const int32_t brick = freeBricks_.back();
  freeBricks_.pop_back();
  const int32_t dim = kStartBrickDim;
  std::vector<int32_t> starts(size_t(dim) * dim * dim);
  int32_t previous = tetSlot_.at(r.tetIds.front());
  for (int k = 0; k < dim; ++k)
    for (int j = 0; j < dim; ++j)
      for (int i = 0; i < dim; ++i) {
        const glm::dvec3 centre = glm::dvec3(grid_.min) + (glm::dvec3(key.x, key.y, key.z) +
                                                           (glm::dvec3(i, j, k) + 0.5) / double(dim)) *
                                                              double(grid_.cellSize);
        int32_t node = r.root;
        while (node >= 0) node = cellGridChild(r.nodes[size_t(node)], centre);
        const int32_t leaf = bspLeafTet(node);
        int32_t cur = leaf >= 0 ? tetSlot_.at(uint32_t(leaf)) : previous;
        cur = startBrickWalk(pool_, cur, glm::vec3(centre));
        starts[size_t(i + dim * (j + dim * k))] = cur;
        previous = cur;
      }
  writeBrick(brick, starts);
  insertCell(key, brick);
  sectors_[key] = brick;
  sectorTets_[key] = std::move(r.tetIds);
  sectorProbes_[key] = std::move(r.probeIds);
  return {};
}

void GpuSectorPool::evict(const SectorKey& which) {
  const SectorKey key = which;  // `which` may be a key of the maps erased below (loadedTets())
  const auto it = sectors_.find(key);
  if (it == sectors_.end()) return;
  eraseCell(key);
  freeBricks_.push_back(it->second);
  sectors_.erase(it);
  std::vector<uint32_t> tets = std::move(sectorTets_[key]), probes = std::move(sectorProbes_[key]);
  sectorTets_.erase(key);
  sectorProbes_.erase(key);
  for (uint32_t id : tets) {
    const auto t = tetSlot_.find(id);
    const int32_t s = t->second;
    if (--tetRefs_[size_t(s)] > 0) continue;
    unlinkFaces(s);
    tetSlot_.erase(t);
    if (occlusion_) {
      const TetOcclusion rec = pool_.occlusion.tets[size_t(s)];
      if (rec.kind() == kOcclusionPlanes) freePlanes_.push_back(occSlot_[size_t(s)]);
      if (rec.kind() == kOcclusionShadowMaps) freeShadows_.push_back(occSlot_[size_t(s)]);
      occSlot_[size_t(s)] = -1;
      pool_.occlusion.tets[size_t(s)] = TetOcclusion{};
    }
    // The freed slot's bytes stay as they were: nothing links to it, no brick names it.
    pool_.tets[size_t(s)] = Tet{{0, 0, 0, 0}, {-1, -1, -1, -1}};
    freeTets_.push_back(s);
  }
  for (uint32_t id : probes) {
    const auto p = probeSlot_.find(id);
    if (--probeRefs_[size_t(p->second)] > 0) continue;
    freeProbes_.push_back(p->second);
    probeSlot_.erase(p);
  }
}

}  // namespace tetraprobe
