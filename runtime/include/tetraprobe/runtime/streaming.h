// Streaming a level by sector: an engine keeps only the 16 m cells near the camera in memory and answers
// everywhere else from a coarse probe set the file always holds (docs/streaming.md). The level file carries
// an optional STRM section (docs/level_format.md) naming, per sector (one cell of the level's cell grid), the
// tets whose bounding boxes touch it, their probes and the cell's BSP; `tetraprobe stream` adds it to a baked
// level. Permissive: standard library and GLM only.
//
// Contract: in a loaded sector, at a point inside the level's tets (inside its probe hull), query() returns
// exactly (bit for bit) what ProbeQuery::irradiance on the fully loaded level returns; elsewhere (the sector
// not loaded, no sector there, or outside the hull, where the full level extrapolates through its outer
// cells) it returns the coarse set's answer: finite, but without occlusion and at the coarse spacing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {

// A sector: integer cell coordinates of the level's cell grid (cell_grid.h): the cell covers
// min + [key, key + 1) * cellSize (local frame) per axis.
struct SectorKey {
  int32_t x = 0, y = 0, z = 0;
  bool operator<(const SectorKey& o) const { return x != o.x ? x < o.x : y != o.y ? y < o.y : z < o.z; }
  bool operator==(const SectorKey& o) const { return x == o.x && y == o.y && z == o.z; }
};

// One sector's records as the file holds them (global indices: the level's own tet and probe numbers).
struct SectorRecords {
  std::vector<uint32_t> tetIds, probeIds;  // increasing
  std::vector<Tet> tets;                   // global probe indices; neighbours -1 (not stored per sector)
  std::vector<glm::vec3> positions;        // probeIds[k]'s position (local frame)
  std::vector<ShRgb> sh;                   // probeIds[k]'s SH
  std::vector<TetOcclusion> occ;       // tetIds[k]'s record (offsets as in the file); empty without occlusion
  std::vector<OcclusionPlane> planes;  // the sector's plane tets' planes, in tet order
  std::vector<uint8_t> blocks;         // its shadow-map tets' blocks, in tet order
  std::vector<BspNode> nodes;          // the cell's BSP: children >= 0 index `nodes`; leaves name global tets
  int32_t root = kEmptyLeaf;
  // Bytes the records hold (vector sizes).
  size_t bytes() const;
};

class StreamingLevel {
 public:
  StreamingLevel();
  ~StreamingLevel();
  StreamingLevel(const StreamingLevel&) = delete;
  StreamingLevel& operator=(const StreamingLevel&) = delete;

  // Opens a level file with a STRM section. Reads and checks only the framing and the index: the header
  // and the section table with the checks loadLevel makes (level_file.h: version, CRCs, flags, repeated or
  // unknown required sections, sizes), the occlusion section's 24-byte header, and the index's header,
  // sector records (44 bytes a sector) and coarse set, against the index's own CRC; then builds the coarse
  // set's query. Holds the file open. Nothing of the fine level is read yet: a sector's bytes are read, and
  // checked against the sector's CRC, by load(). Never throws; on failure the object is closed and the
  // message names the file and the problem (kUnsupportedVersion naming both versions for a file of another
  // format version; kCorrupt for a bad or missing index).
  LevelResult open(const std::string& path);
  // Bytes the last successful open() read from the file (the framing and the index; not the sectors).
  uint64_t bytesReadAtOpen() const { return openBytesRead_; }

  // The sectors the file holds, in increasing key order.
  const std::vector<SectorKey>& sectors() const { return keys_; }
  // The sector of a world-space point (whether or not the file has one there).
  SectorKey sectorOf(const glm::dvec3& world) const;
  bool hasSector(const SectorKey& key) const;
  bool isLoaded(const SectorKey& key) const { return loaded_.count(key) > 0; }

  // Reads a sector's references and BSP from the index and its tets, probes, SH and occlusion from the
  // level's sections (seeks), checks them against the sector's CRC, and rebuilds the loaded level
  // (the union of the loaded sectors; cost proportional to it). Loading a loaded sector does nothing.
  // kCorrupt when the sector's bytes fail their CRC or its records fail validation (validateLevel on the
  // loaded level, and a face shared by three loaded tets), leaving the other sectors loaded as they were;
  // the key not being a sector of the file is kCorrupt too. Not to be called while other threads query.
  LevelResult load(const SectorKey& key);
  // Reads and checks one sector's records as load() does (the sector's CRC, index ranges, probe and BSP
  // references within the sector), without loading it: for a consumer that keeps its own copy of the
  // loaded sectors, such as the GPU pool (gpu_sector_pool.h). Cost proportional to the sector. The object
  // is not changed (the file's read position aside); not to be called while other threads use it.
  LevelResult readSector(const SectorKey& key, SectorRecords& out);
  // The grid the sectors are cells of (min and cellSize; no slots), local frame, and the level's origin.
  const CellGrid& sectorGrid() const { return grid_; }
  const glm::dvec3& origin() const { return origin_; }
  // Whether the file holds occlusion records (each sector's tets then carry theirs).
  bool hasOcclusion() const;

  // Drops a sector and rebuilds the loaded level from the others. Unloading an absent sector does nothing.
  void unload(const SectorKey& key);

  // Irradiance E in W/m^2 at a world-space point with unit normal `normal` (see the contract above).
  // Thread-safe for concurrent const use.
  glm::vec3 query(const glm::dvec3& world, const glm::vec3& normal) const;
  // Whether query() answers from the loaded sectors (true) or the coarse set (false) at this point: the
  // point's sector is loaded and the loaded level's walk ends inside a tet. (query() locates twice there:
  // once to decide, once in ProbeQuery::irradiance.)
  bool answersFromLoaded(const glm::dvec3& world) const;

  // Bytes held: the index, the coarse set and its query's own data, the loaded sectors' records, and the
  // loaded level built from them with its query's own data (vector sizes, not allocator overhead).
  size_t bytesInUse() const;

  const Level& coarse() const { return coarse_; }
  // The coarse set's query (valid while open): what query() answers with outside the loaded sectors.
  const ProbeQuery& coarseQuery() const { return *coarseQuery_; }
  const Level& loadedLevel() const { return fine_; }

 private:
  using Sector = SectorRecords;
  struct File;
  LevelResult openChecked(const std::string& path);
  // Joins the loaded sectors into fine_ and builds its query: "" or why the joined level is invalid (a face
  // of three tets, or what validateLevel refuses), leaving fine_ empty.
  std::string rebuild();
  void close();

  std::string path_;
  std::unique_ptr<File> file_;
  uint64_t openBytesRead_ = 0;
  std::vector<SectorKey> keys_;
  std::vector<uint8_t> index_;  // the STRM section's sector records
  Level coarse_;
  std::unique_ptr<ProbeQuery> coarseQuery_;
  std::map<SectorKey, std::unique_ptr<Sector>> loaded_;
  Level fine_;  // the loaded sectors as one level (local indices)
  std::unique_ptr<ProbeQuery> fineQuery_;
  glm::dvec3 origin_{0.0};
  CellGrid grid_;  // the full grid's frame (min, cellSize); no slots
};

}  // namespace tetraprobe
