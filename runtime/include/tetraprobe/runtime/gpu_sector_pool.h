// GPU streaming by sector: the six buffers of the GLSL lookup (gpu_layout.h) laid out once at a fixed
// capacity, with a streamed level's sectors (streaming.h: one 16 m cell each) written into and evicted from
// slots of them as a camera moves. The shader is the ordinary lookup (tetraprobe.glsl, unchanged): the pool
// is a level whose tets, probes, occlusion records and start bricks live in slots, with a free list each.
// Permissive: standard library and GLM only (Vulkan: vulkan_upload.h uploads the bytes and the ranges).
//
// What the buffers hold:
// - The coarse set (StreamingLevel::coarse()) resident for good in the first tet and probe slots, with its
//   start grid (TetraprobeGrid) and outer cells: where a point's cell is not loaded, the start bricks have
//   no entry, the walk starts from the coarse start grid and answers from the coarse set, as
//   StreamingLevel::query does.
// - Per loaded sector: its tets (a tet shared by loaded sectors is held once, reference-counted), their
//   probes with SH, their occlusion records (a plane block of 7 uints or a 64-byte shadow map, each from a
//   slot pool), and the cell's start brick (16^3 start tets, one brick slot) under the cell grid's hash
//   (linear probing; eviction shifts the probe chain back, so no tombstones).
// - Neighbours linked among the resident tets by the faces they share (a face whose other tet is not
//   resident is cut), and each tet's face-blend flags (face_blend.h) recomputed when a neighbour comes or goes.
//
// Contract: with the same sectors loaded, at a point where StreamingLevel::answersFromLoaded is true, the
// lookup on these buffers returns what it returns on the full level's buffers (packLevelBuffers), bit for
// bit: the same tets in the same vertex order, with the same probes, SH and occlusion, reached by walks that
// the sector's tets (those touching the cell, and their face neighbours) contain; the start tets may differ,
// which moves no answer (tests/render/test_gpu_sector_pool.cpp renders both). Elsewhere the coarse set
// answers (finite, no occlusion).
//
// Cost: load() and evict() touch what the sector holds and the resident tets that share a face with it:
// O(sector), whatever the level's or the pool's size, and mark exactly the bytes they wrote as dirty for
// the next upload (takeDirtyRanges()).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "tetraprobe/runtime/gpu_layout.h"
#include "tetraprobe/runtime/gpu_tets.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/shader_variant.h"
#include "tetraprobe/runtime/streaming.h"

namespace tetraprobe {

// Slots of the pool, besides the coarse set's.
struct GpuPoolCapacity {
  uint32_t sectors = 0;     // sectors resident at once (start bricks)
  uint32_t tets = 0;        // tets
  uint32_t probes = 0;      // probes
  uint32_t planeTets = 0;   // tets with splitting-plane occlusion
  uint32_t shadowTets = 0;  // tets with shadow-map occlusion
};

// One span of one buffer that changed: bytes [offset, offset + bytes) of binding `binding`.
struct GpuBufferRange {
  uint32_t binding = 0;
  uint64_t offset = 0, bytes = 0;
};

// Per-sector sizes (one read of every sector, O(level)): what a capacity is sized from.
struct GpuSectorSizes {
  SectorKey key;
  uint32_t tets = 0, probes = 0, planeTets = 0, shadowTets = 0;
};
// Reads every sector of `level` once (readSector) and counts its records; false (and `error`) when one fails.
bool measureSectors(StreamingLevel& level, std::vector<GpuSectorSizes>& out, std::string* error = nullptr);
// A capacity that holds any `sectors` of the measured sectors at once: per kind, the sum of the `sectors`
// largest counts (an upper bound: a tet two resident sectors share takes one slot).
GpuPoolCapacity gpuPoolCapacityFor(const std::vector<GpuSectorSizes>& sizes, uint32_t sectors);
// The bytes of the six buffers a pool of `capacity` takes for `level` (its coarse set and grid), as
// GpuSectorPool::bytes() reports after init: for choosing `sectors` under a GPU memory budget.
size_t gpuPoolBytes(const StreamingLevel& level, const GpuPoolCapacity& capacity);

class GpuSectorPool {
 public:
  // Lays out the buffers for `level` (open) at `capacity`: the coarse set resident, nothing else loaded,
  // every byte dirty (the first upload copies all of them). "" or why not (level not open, a capacity whose
  // tets or probes exceed the packing's 2^31, an occlusion offset beyond the GPU record's 2^24, SH the GPU
  // record cannot hold). The level must stay open while the pool loads from it.
  std::string init(StreamingLevel& level, const GpuPoolCapacity& capacity,
                   int32_t maxWalkSteps = 4096 /* kGpuDefaultMaxWalkSteps */);

  // Reads the sector (StreamingLevel::readSector: checked against its CRC) and writes it into free slots.
  // Loading a loaded sector does nothing. kTooLarge when a slot pool lacks room (nothing written), the
  // read's failure otherwise; the pool stays as it was on failure.
  LevelResult load(const SectorKey& key);
  // Frees the sector's brick and every tet and probe no other loaded sector holds. Absent: nothing.
  void evict(const SectorKey& key);
  bool isLoaded(const SectorKey& key) const { return sectors_.count(key) > 0; }
  size_t loadedSectors() const { return sectors_.size(); }
  const std::map<SectorKey, std::vector<uint32_t>>& loadedTets() const { return sectorTets_; }

  // CPU queries on what the pool holds, for objects and other CPU consumers of a streamed level: the
  // irradiance at a world point with a unit normal, from the loaded sectors where answersFromLoaded(), else
  // from the coarse set. Inside a loaded sector's tets it is what ProbeQuery::irradiance on the full level
  // returns (bit for bit, as StreamingLevel::query), with no joined level to rebuild on a load. The point's
  // cell's start brick starts ProbeQuery's walk (locateByWalk), which must end in a tet without leaving
  // through a cut face. Thread-safe for concurrent const use (not during load or evict).
  glm::vec3 irradiance(const glm::dvec3& world, const glm::vec3& normal) const;
  bool answersFromLoaded(const glm::dvec3& world) const;

  // The buffers' bytes (the CPU mirror of the GPU buffers, sizes fixed by init).
  const PackedLevelBuffers& buffers() const { return buffers_; }
  // The byte spans written since the last call (merged, sorted by binding and offset), then forgotten.
  std::vector<GpuBufferRange> takeDirtyRanges();
  // The variant to specialize the lookup with: the full level's features (planes and shadow maps when the
  // file has such records; outer cells for the coarse set; the start bricks) and the pool's tet packing.
  ShaderVariant variant() const { return variant_; }

  // Bytes of the six buffers (what the GPU holds, fixed), and the bytes of the slots in use (records of the
  // resident tets, probes, occlusion and bricks, and the coarse set's part).
  size_t bytes() const;
  size_t bytesInUse() const;
  uint32_t residentTets() const { return uint32_t(pool_.tets.size() - freeTets_.size() - coarseTets_); }
  uint32_t residentProbes() const {
    return uint32_t(pool_.probes.size() - freeProbes_.size() - coarseProbes_);
  }

 private:
  struct FaceKey {
    uint32_t v[3];
    bool operator==(const FaceKey& o) const { return v[0] == o.v[0] && v[1] == o.v[1] && v[2] == o.v[2]; }
  };
  struct FaceHash {
    size_t operator()(const FaceKey& k) const {
      uint64_t h = uint64_t(k.v[0]) * 0x9E3779B97F4A7C15ull ^ uint64_t(k.v[1]) * 0xC2B2AE3D27D4EB4Full ^
                   uint64_t(k.v[2]) * 0x165667B19E3779F9ull;
      return size_t(h ^ (h >> 29));
    }
  };
  FaceKey faceKey(int32_t slot, int k) const;
  void markDirty(uint32_t binding, uint64_t offset, uint64_t bytes);
  void writeTet(int32_t slot);
  void writeOcclusionHeader(int32_t slot);
  void writeStarHeaders(const std::vector<int32_t>& slots);
  void writeProbe(int32_t slot);
  void writeBrick(int32_t brick, const std::vector<int32_t>& startTets);
  void writeCellSlot(size_t h);
  void linkFaces(int32_t slot);
  void unlinkFaces(int32_t slot);
  bool insertCell(const SectorKey& key, int32_t brick);
  bool locateLoaded(const glm::dvec3& world, Location& loc) const;
  void eraseCell(const SectorKey& key);

  StreamingLevel* level_ = nullptr;
  GpuPoolCapacity cap_;
  GpuTetPacking packing_;
  ShaderVariant variant_;
  bool occlusion_ = false;
  uint32_t coarseTets_ = 0, coarseProbes_ = 0;
  PackedLevelBuffers buffers_;
  std::vector<GpuBufferRange> dirty_;
  // Byte offsets in the buffers.
  uint64_t tetRecords_ = 0, shOffset_ = 0, occHeaders_ = 0, occPlanes_ = 0, occShadows_ = 0;
  uint64_t cellSlots_ = 0, cellBricks_ = 0;
  size_t tableSlots_ = 0;
  // The CPU copy of what the slots hold (pool indices): tets, probes, SH and occlusion as a Level, so the
  // face-blend flags are computed by face_blend.h on it (plane slot p at planes [3p, 3p + 3), shadow slot s
  // at block s).
  Level pool_;
  std::vector<uint32_t> probeGlobal_;  // slot -> the file's probe index (coarse slots: unused; faces' keys)
  std::vector<uint32_t> tetRefs_, probeRefs_;  // loaded sectors holding the slot (0: free)
  std::vector<int32_t> occSlot_;               // tet slot -> its plane or shadow slot, or -1
  std::vector<int32_t> freeTets_, freeProbes_, freePlanes_, freeShadows_, freeBricks_;
  std::unordered_map<uint32_t, int32_t> tetSlot_, probeSlot_;  // the file's index -> slot (resident only)
  std::unordered_map<FaceKey, int32_t, FaceHash> faces_;       // a resident tet's face -> 4 * slot + k
  std::vector<CellSlot> table_;                                // the cells' hash table (root = brick)
  std::vector<int32_t> brickStarts_;                           // the bricks' start tets (slots), unpacked
  std::map<SectorKey, int32_t> sectors_;                       // loaded sector -> its brick
  std::map<SectorKey, std::vector<uint32_t>> sectorTets_;      // loaded sector -> its tets (file indices)
  std::map<SectorKey, std::vector<uint32_t>> sectorProbes_;
  CellGrid grid_;  // the sectors' grid frame
};

}  // namespace tetraprobe
