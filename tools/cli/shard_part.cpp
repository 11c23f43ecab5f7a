// Part files of a sharded bake: encode, decode, checksum (shard_part.h). The bytes are written field by field,
// so they do not depend on the compiler; the checksum is FNV-1a 64 (Fowler, Noll, Vo).
#include "shard_part.h"

#include <climits>
#include <cstring>
#include <vector>

#include "state_io.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/file_io.h"

namespace tetraprobe::cli {

namespace {

constexpr char kMagic[8] = {'T', 'P', 'S', 'H', 'A', 'R', 'D', '3'};
constexpr size_t kRecordBytes = 4 + kProbeStateBytes;

struct Hasher {
  uint64_t h = 0xcbf29ce484222325ull;
  template <class T>
  void pod(const T& v) {
    h = fnv1a(&v, sizeof(T), h);
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    pod(uint64_t(v.size()));
    if (!v.empty()) h = fnv1a(v.data(), v.size() * sizeof(T), h);
  }
};

}  // namespace

uint64_t sceneContentHash(const Scene& s) {
  static_assert(sizeof(glm::vec3) == 12 && sizeof(glm::uvec3) == 12 && sizeof(glm::vec2) == 8);
  Hasher h;
  h.vec(s.positions);
  h.vec(s.triangles);
  h.vec(s.triangleMaterial);
  h.pod(uint64_t(s.materials.size()));
  for (const Material& m : s.materials) {
    h.pod(m.albedo);
    h.pod(m.emission);
    h.pod(m.transmission);
    h.pod(m.alphaTexture);
    h.pod(m.alphaCutoff);
  }
  h.pod(uint64_t(s.alphaTextures.size()));
  for (const AlphaTexture& t : s.alphaTextures) {
    h.pod(t.width);
    h.pod(t.height);
    h.vec(t.alpha);
    h.pod(uint8_t(t.wrapU));
    h.pod(uint8_t(t.wrapV));
  }
  h.vec(s.cutoutTriangles);
  h.vec(s.cutoutUvs);
  h.pod(uint64_t(s.lights.size()));
  for (const Light& l : s.lights) {
    h.pod(int32_t(l.type));
    h.pod(l.position);
    h.pod(l.direction);
    h.pod(l.intensity);
    h.pod(l.innerConeRad);
    h.pod(l.outerConeRad);
    h.pod(l.angularRadiusRad);
    h.pod(l.radius);
  }
  h.pod(s.skyRadiance);
  h.pod(s.skyHorizonRadiance);
  h.pod(uint64_t(s.cameras.size()));
  for (const Camera& c : s.cameras) {
    h.pod(c.eye);
    h.pod(c.target);
    h.pod(c.up);
    h.pod(c.fovYDeg);
  }
  h.pod(uint64_t(s.fineVolumes.size()));
  for (const Volume& v : s.fineVolumes) {
    h.pod(v.min);
    h.pod(v.max);
  }
  return h.h;
}

void writeShardPart(const std::string& path, const ShardPart& part) {
  ByteWriter w;
  w.bytes.assign(kMagic, kMagic + 8);
  w.put(uint32_t(part.stage));
  w.put(part.index);
  w.put(part.count);
  w.put(part.probeCount);
  w.put(part.sceneHash);
  w.put(part.bake.floor);
  w.put(uint64_t(part.options.size()));
  w.bytes += part.options;
  w.put(uint64_t(part.bake.probes.size()));
  for (size_t k = 0; k < part.bake.probes.size(); ++k) {
    w.put(part.bake.probes[k]);
    putProbeState(w, part.bake.states[k]);
  }
  w.seal();
  std::string error;
  if (!writeFileAtomic(path, w.bytes, &error)) throw std::runtime_error(error);
}

ShardPart readShardPart(const std::string& path) {
  std::vector<char> bytes;
  std::string error;
  if (!readFile(path, bytes, &error)) throw InputError(error);
  ByteReader r(bytes, "shard part", path);
  r.open(kMagic);
  ShardPart p;
  const uint32_t stage = r.get<uint32_t>();
  if (stage < 1 || stage > 3) r.fail("unknown stage " + std::to_string(stage));
  p.stage = PartStage(stage);
  p.index = r.get<uint32_t>();
  p.count = r.get<uint32_t>();
  if (p.count == 0 || p.index >= p.count)
    r.fail("shard index " + std::to_string(p.index) + " of " + std::to_string(p.count));
  p.probeCount = r.get<uint64_t>();
  if (p.probeCount > uint64_t(INT32_MAX)) r.fail("implausible probe count " + std::to_string(p.probeCount));
  p.sceneHash = r.get<uint64_t>();
  p.bake.floor = r.get<double>();
  const uint64_t optionBytes = r.get<uint64_t>();
  r.need(optionBytes);
  p.options = r.text(size_t(optionBytes));
  const uint64_t k = r.get<uint64_t>();
  if (k > p.probeCount || k > r.left() / kRecordBytes) r.fail("bad record count");
  p.bake.probes.resize(size_t(k));
  p.bake.states.resize(size_t(k));
  for (size_t n = 0; n < k; ++n) {
    p.bake.probes[n] = r.get<uint32_t>();
    if (p.bake.probes[n] >= p.probeCount || (n > 0 && p.bake.probes[n] <= p.bake.probes[n - 1]))
      r.fail("probe indices out of range or not increasing");
    p.bake.states[n] = getProbeState(r);
  }
  r.finish();
  return p;
}

void checkSameBake(const ShardPart& p, const ShardPart& first, const std::string& path) {
  if (p.count != first.count)
    throw InputError("shard part " + path + " is one of " + std::to_string(p.count) + " shards, not " +
                     std::to_string(first.count));
  if (p.sceneHash != first.sceneHash) throw InputError("shard part " + path + " baked a different scene");
  if (p.options != first.options) throw InputError("shard part " + path + " baked with different options");
  if (p.probeCount != first.probeCount)
    throw InputError("shard part " + path + " placed " + std::to_string(p.probeCount) + " probes, not " +
                     std::to_string(first.probeCount));
}

void checkShardSet(const std::vector<ShardPart>& parts, const std::vector<std::string>& paths,
                   PartStage stage) {
  static const char* const kStageNames[] = {"", "round-1 (--round 1)", "shard", "floor"};
  const ShardPart& first = parts.at(0);
  std::vector<int> seen(first.count, -1);
  std::vector<uint8_t> probe(size_t(first.probeCount), 0);
  for (size_t k = 0; k < parts.size(); ++k) {
    const ShardPart& p = parts[k];
    if (p.stage != stage)
      throw InputError("shard part " + paths[k] + " is a " + kStageNames[uint32_t(p.stage)] +
                       " part, not a " + kStageNames[uint32_t(stage)] + " part");
    checkSameBake(p, first, paths[k]);
    if (std::memcmp(&p.bake.floor, &first.bake.floor, sizeof(double)) != 0)
      throw InputError("shard part " + paths[k] + " has another floor (different pass-1 results)");
    if (seen[p.index] >= 0)
      throw InputError("shard " + std::to_string(p.index) + " given twice (" + paths[size_t(seen[p.index])] +
                       ", " + paths[k] + ")");
    seen[p.index] = int(k);
    for (uint32_t i : p.bake.probes) {
      if (probe[i]) throw InputError("shard part " + paths[k] + " repeats probe " + std::to_string(i));
      probe[i] = 1;
    }
  }
  for (uint32_t i = 0; i < first.count; ++i)
    if (seen[i] < 0)
      throw InputError("shard " + std::to_string(i) + " of " + std::to_string(first.count) + " is missing");
}

}  // namespace tetraprobe::cli
