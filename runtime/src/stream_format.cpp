// The streaming index's bytes and checksums (stream_format.h; layout: docs/level_format.md, section STRM).
// Opening a streamed level reads the framing and the index, whose own CRC covers its header, its sector
// records and the coarse set; each sector carries a CRC of every byte it reads, here and in the level's
// sections, so a sector is checked when it is loaded and the file is never read end to end.
#include "stream_format.h"

#include "byte_order.h"

#include <algorithm>
#include <bit>
#include <climits>
#include <cmath>
#include <cstring>

#include "tetraprobe/runtime/crc32.h"
#include "tetraprobe/runtime/occlusion_data.h"
#include "tetraprobe/runtime/sh.h"
#include "tetraprobe/runtime/sh_half.h"

namespace tetraprobe::runtime_detail {
namespace {

constexpr uint64_t kMaxCount = uint64_t(INT32_MAX);
constexpr uint64_t kMaxRefs = uint64_t(1) << 36;
constexpr uint64_t kOcclusionHeaderBytes = 24, kOcclusionRecordBytes = 8, kOcclusionPlaneBytes = 8;

// Reads `n` bytes at `at` onto the end of `out`.
bool append(ByteSource& src, uint64_t at, size_t n, std::vector<uint8_t>& out) {
  const size_t old = out.size();
  out.resize(old + n);
  return n == 0 || src.read(at, out.data() + old, n);
}

// Pieces of the file to append in order, each (offset, bytes): a sector's records lie in increasing order
// with gaps (the sector's tets among the level's), so pieces less than kCoalesceGap apart are read in one
// read and copied out: a few reads a sector instead of one seek and read per record.
using Pieces = std::vector<std::pair<uint64_t, uint32_t>>;
constexpr uint64_t kCoalesceGap = 4096, kMaxSpan = uint64_t(1) << 20;

bool appendPieces(ByteSource& src, const Pieces& pieces, std::vector<uint8_t>& out) {
  std::vector<uint8_t> span;
  for (size_t i = 0; i < pieces.size();) {
    const uint64_t start = pieces[i].first;
    uint64_t end = start + pieces[i].second;
    size_t j = i + 1;
    while (j < pieces.size() && pieces[j].first >= pieces[j - 1].first &&
           pieces[j].first <= end + kCoalesceGap && pieces[j].first + pieces[j].second - start <= kMaxSpan)
      end = std::max(end, pieces[j].first + pieces[j].second), ++j;
    span.resize(size_t(end - start));
    if (!span.empty() && !src.read(start, span.data(), span.size())) return false;
    for (; i < j; ++i)
      out.insert(out.end(), span.begin() + ptrdiff_t(pieces[i].first - start),
                 span.begin() + ptrdiff_t(pieces[i].first - start + pieces[i].second));
  }
  return true;
}

// Reads `count` increasing references below `limit` at `at`.
bool readRefs(ByteSource& src, uint64_t at, uint32_t count, uint64_t limit, std::vector<uint32_t>& ids,
              std::vector<uint8_t>& raw) {
  raw.clear();
  if (!append(src, at, 4 * size_t(count), raw)) return false;
  ids.resize(count);
  for (uint32_t k = 0; k < count; ++k) {
    ids[k] = u32At(raw.data() + 4 * size_t(k));
    if (ids[k] >= limit || (k > 0 && ids[k] <= ids[k - 1])) return false;
  }
  return true;
}

// Walks the index of a file in memory: checks it (patch == null) or writes its CRCs (patch == data).
std::string walkIndex(const uint8_t* data, size_t size, const LevelFileLayout& layout, uint8_t* patch,
                      bool strict) {
  MemorySource src(data, size);
  StreamRecords rec;
  if (std::string e = locateStreamRecords(layout, src, rec); !e.empty()) return e;
  StreamHeader h;
  if (rec.strmBytes < kStreamHeaderBytes) return "streaming index shorter than its header";
  if (std::string e = parseStreamHeader(data + rec.strm, rec.strmBytes, h); !e.empty()) return e;
  const uint8_t* sectors = data + rec.strm + kStreamHeaderBytes;
  StreamSector previous;
  SectorBytes bytes;
  for (uint32_t i = 0; i < h.sectors; ++i) {
    const StreamSector s = parseStreamSector(sectors + kStreamSectorBytes * i);
    const std::string where = "streaming sector " + std::to_string(i) + ": ";
    if (std::string e = checkStreamSector(s, i > 0 ? &previous : nullptr, h); !e.empty()) {
      if (strict) return where + e;
      continue;
    }
    previous = s;
    if (std::string e = readSectorBytes(src, rec, h, s, bytes); !e.empty()) {
      if (strict) return where + e;
      continue;
    }
    if (patch)
      putU32(patch + rec.strm + kStreamHeaderBytes + kStreamSectorBytes * i + kStreamSectorCrcAt, bytes.crc);
    else if (bytes.crc != s.crc)
      return where + "checksum mismatch";
  }
  const uint32_t crc = streamIndexCrc(data + rec.strm, sectors, h, data + rec.strm + h.coarseAt());
  if (patch)
    putU32(patch + rec.strm + kStreamIndexCrcAt, crc);
  else if (crc != h.crc)
    return "streaming index checksum mismatch";
  return {};
}

}  // namespace

bool MemorySource::read(uint64_t at, void* out, size_t n) {
  if (at > size_ || n > size_ - at) return false;
  if (n > 0) std::memcpy(out, data_ + at, n);
  return true;
}

bool FileSource::open(const std::string& path) {
  in_.open(path, std::ios::binary | std::ios::ate);
  if (!in_) return false;
  const auto end = in_.tellg();
  if (end < 0) return false;
  size_ = uint64_t(end);
  return true;
}

bool FileSource::read(uint64_t at, void* out, size_t n) {
  if (at > size_ || n > size_ - at) return false;
  in_.clear();
  in_.seekg(std::streamoff(at));
  in_.read(static_cast<char*>(out), std::streamsize(n));
  bytesRead_ += n;
  return bool(in_);
}

std::string parseStreamHeader(const uint8_t* x, uint64_t sectionBytes, StreamHeader& h) {
  h = StreamHeader{};
  const uint32_t version = u32At(x);
  if (version != kStreamVersion)
    return "streaming index version " + std::to_string(version) + " (this reader understands version " +
           std::to_string(kStreamVersion) + ")";
  h.sectors = u32At(x + 4);
  for (int a = 0; a < 3; ++a) h.min[a] = std::bit_cast<float>(u32At(x + 8 + 4 * a));
  h.cellSize = std::bit_cast<float>(u32At(x + 20));
  h.tetRefs = u64At(x + 24);
  h.probeRefs = u64At(x + 32);
  h.nodes = u64At(x + 40);
  h.coarseProbes = u32At(x + 48);
  h.coarseTets = u32At(x + 52);
  h.crc = u32At(x + kStreamIndexCrcAt);
  if (h.tetRefs > kMaxRefs || h.probeRefs > kMaxRefs || h.nodes > kMaxCount || h.coarseProbes > kMaxCount ||
      h.coarseTets > kMaxCount || u32At(x + 60) != 0 || sectionBytes != h.coarseAt() + h.coarseBytes())
    return "streaming index header does not match its size";
  if (!(h.cellSize > 0.0f) || !std::isfinite(h.cellSize) || !std::isfinite(h.min.x) ||
      !std::isfinite(h.min.y) || !std::isfinite(h.min.z))
    return "streaming index: bad grid corner or cell size";
  return {};
}

uint32_t streamIndexCrc(const uint8_t* header, const uint8_t* sectors, const StreamHeader& h,
                        const uint8_t* coarse) {
  uint32_t crc = crc32(header, size_t(kStreamIndexCrcAt));
  crc = crc32(sectors, size_t(h.sectorsBytes()), crc);
  return crc32(coarse, size_t(h.coarseBytes()), crc);
}

StreamSector parseStreamSector(const uint8_t* p) {
  StreamSector s;
  for (int a = 0; a < 3; ++a) s.key[a] = int32_t(u32At(p + 4 * a));
  s.root = int32_t(u32At(p + 12));
  s.tetFirst = u32At(p + 16);
  s.tetCount = u32At(p + 20);
  s.probeFirst = u32At(p + 24);
  s.probeCount = u32At(p + 28);
  s.nodeFirst = u32At(p + 32);
  s.nodeCount = u32At(p + 36);
  s.crc = u32At(p + kStreamSectorCrcAt);
  return s;
}

std::string checkStreamSector(const StreamSector& s, const StreamSector* previous, const StreamHeader& h) {
  if (previous) {
    const int32_t* a = previous->key;
    const int32_t* b = s.key;
    if (!std::lexicographical_compare(a, a + 3, b, b + 3)) return "keys not increasing";
  }
  if (uint64_t(s.tetFirst) + s.tetCount > h.tetRefs || uint64_t(s.probeFirst) + s.probeCount > h.probeRefs ||
      uint64_t(s.nodeFirst) + s.nodeCount > h.nodes)
    return "ranges out of bounds";
  return {};
}

std::string locateStreamRecords(const LevelFileLayout& l, ByteSource& src, StreamRecords& out) {
  out = StreamRecords{};
  // saveLevel writes TETC and OCCL for a level with a streaming index: a sector seeks their records.
  if (l.tetsPacked.present) return "packed tets (TETM) cannot be streamed: re-run tetraprobe stream";
  if (l.occlusionPacked.present)
    return "packed occlusion (OCC2) cannot be streamed: re-run tetraprobe stream";
  if (!l.stream.present) return "no streaming index (add one: tetraprobe stream)";
  out.strm = l.stream.offset;
  out.strmBytes = l.stream.size;
  out.probeCount = l.probeCount;
  out.tetCount = l.tetCount;
  out.probes = l.probes.offset;
  out.sh = l.shHalf.present ? l.shHalf.offset : l.sh.offset;
  out.shRecord = l.shHalf.present ? sizeof(ShHalf) : sizeof(ShRgb);
  if (l.tetsCompact.present) {
    out.tets = l.tetsCompact.offset;
    out.tetIndexBytes = levelProbeIndexBytes(l.probeCount);
    out.tetRecord = 4 * out.tetIndexBytes;
  } else {  // TETS: four i32 probes, then the neighbours (not read)
    out.tets = l.tets.offset;
    out.tetIndexBytes = 4;
    out.tetRecord = 32;
  }
  if (l.occlusion.present) {
    uint8_t c[kOcclusionHeaderBytes];
    if (l.occlusion.size < kOcclusionHeaderBytes || !src.read(l.occlusion.offset, c, sizeof c))
      return "occlusion section shorter than its header";
    out.occl = l.occlusion.offset;
    out.planes = u64At(c + 8);
    out.blocks = u64At(c + 16);
    if (u64At(c) != l.tetCount || out.planes > kOcclusionMaxOffset || out.blocks > kOcclusionMaxOffset ||
        l.occlusion.size != kOcclusionHeaderBytes + kOcclusionRecordBytes * l.tetCount +
                                kOcclusionPlaneBytes * out.planes +
                                uint64_t(kShadowMapBlockBytes) * out.blocks)
      return "occlusion section size does not match its counts";
  }
  return {};
}

std::string readSectorBytes(ByteSource& src, const StreamRecords& rec, const StreamHeader& h,
                            const StreamSector& s, SectorBytes& out) {
  std::vector<uint8_t> tetRefs, probeRefs;
  out.nodes.clear();
  out.tets.clear();
  out.positions.clear();
  out.sh.clear();
  out.occ.clear();
  out.planes.clear();
  out.blocks.clear();
  if (!readRefs(src, rec.strm + h.tetRefsAt() + 4 * uint64_t(s.tetFirst), s.tetCount, rec.tetCount,
                out.tetIds, tetRefs))
    return "tet references out of range or not increasing";
  if (!readRefs(src, rec.strm + h.probeRefsAt() + 4 * uint64_t(s.probeFirst), s.probeCount, rec.probeCount,
                out.probeIds, probeRefs))
    return "probe references out of range or not increasing";
  if (!append(src, rec.strm + h.nodesAt() + kStreamNodeBytes * s.nodeFirst,
              size_t(kStreamNodeBytes * s.nodeCount), out.nodes))
    return "read failed";
  Pieces pieces;
  for (uint32_t t : out.tetIds)
    pieces.emplace_back(rec.tets + rec.tetRecord * t, uint32_t(4 * rec.tetIndexBytes));
  if (!appendPieces(src, pieces, out.tets)) return "read failed";
  pieces.clear();
  for (uint32_t p : out.probeIds) pieces.emplace_back(rec.probes + 12 * uint64_t(p), 12u);
  if (!appendPieces(src, pieces, out.positions)) return "read failed";
  pieces.clear();
  for (uint32_t p : out.probeIds) pieces.emplace_back(rec.sh + rec.shRecord * p, uint32_t(rec.shRecord));
  if (!appendPieces(src, pieces, out.sh)) return "read failed";
  if (rec.occl != 0) {
    const uint64_t recordsAt = rec.occl + kOcclusionHeaderBytes,
                   planesAt = recordsAt + kOcclusionRecordBytes * rec.tetCount,
                   blocksAt = planesAt + kOcclusionPlaneBytes * rec.planes;
    pieces.clear();
    for (uint32_t t : out.tetIds)
      pieces.emplace_back(recordsAt + kOcclusionRecordBytes * t, kOcclusionRecordBytes);
    if (!appendPieces(src, pieces, out.occ)) return "read failed";
    Pieces planes, blocks;
    for (size_t k = 0; k < out.tetIds.size(); ++k) {
      const uint32_t t = out.tetIds[k];
      const uint8_t* r = out.occ.data() + kOcclusionRecordBytes * k;
      const TetOcclusion o{u32At(r), u32At(r + 4)};
      if (o.kind() == kOcclusionPlanes) {
        if (o.planeCount() < 1 || uint64_t(o.offset()) + o.planeCount() > rec.planes)
          return "occlusion of tet " + std::to_string(t) + ": planes out of range";
        planes.emplace_back(planesAt + kOcclusionPlaneBytes * o.offset(),
                            uint32_t(kOcclusionPlaneBytes * o.planeCount()));
      } else if (o.kind() == kOcclusionShadowMaps) {
        if (o.offset() >= rec.blocks)
          return "occlusion of tet " + std::to_string(t) + ": shadow map out of range";
        blocks.emplace_back(blocksAt + uint64_t(kShadowMapBlockBytes) * o.offset(),
                            uint32_t(kShadowMapBlockBytes));
      } else if (o.kind() != kOcclusionNone) {
        return "occlusion of tet " + std::to_string(t) + ": unknown kind " + std::to_string(o.kind());
      }
    }
    if (!appendPieces(src, planes, out.planes) || !appendPieces(src, blocks, out.blocks))
      return "read failed";
  }
  uint32_t crc = crc32(tetRefs.data(), tetRefs.size());
  crc = crc32(probeRefs.data(), probeRefs.size(), crc);
  for (const std::vector<uint8_t>* b :
       {&out.nodes, &out.tets, &out.positions, &out.sh, &out.occ, &out.planes, &out.blocks})
    crc = crc32(b->data(), b->size(), crc);
  out.crc = crc;
  return {};
}

std::string checkStreamIndex(const uint8_t* data, size_t size, const LevelFileLayout& layout) {
  return walkIndex(data, size, layout, nullptr, true);
}

std::string sealStreamIndex(uint8_t* data, size_t size, const LevelFileLayout& layout, StreamSeal mode) {
  return walkIndex(data, size, layout, data, mode == StreamSeal::kAll);
}

}  // namespace tetraprobe::runtime_detail
