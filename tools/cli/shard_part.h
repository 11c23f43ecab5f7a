// Part files of a sharded bake (`tetraprobe bake --shard I/N`, `tetraprobe merge`; docs/distributed.md):
// one shard's probe states after bake passes 1-2, with what the merge needs to check the shards belong
// together. Build side; not a level file and not for engines.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/scene/scene.h"

namespace tetraprobe::cli {

// What a part holds (docs/distributed.md).
enum class PartStage : uint32_t {
  kPass1 = 1,   // round 1 of the two-round protocol: the own probes' states after pass 1 (floor NaN)
  kPass12 = 2,  // the own probes' states after passes 1-2 and the floor: what `merge` joins
  kFloor = 3,   // `merge --floor` over round-1 parts: the floor only (no probes), for round 2
};

struct ShardPart {
  PartStage stage = PartStage::kPass12;
  uint32_t index = 0, count = 0;  // shard `index` of `count`
  uint64_t probeCount = 0;        // probes the deterministic placement gave (all shards)
  uint64_t sceneHash = 0;         // sceneContentHash of the loaded scene
  std::string options;            // the bake's options, canonical (every one that can change the level)
  ShardBake bake;                 // the shard's probes' states and the floor
};

// What `merge` hands the bake: the shards' states, joined, and what they were baked against.
struct MergedShards {
  uint64_t sceneHash = 0;
  uint64_t probeCount = 0;
  ShardBake bake;  // every shard's probes and states, in shard order
  // `merge --farm DIR --workers N` (trace_farm.h): the merge's tracing goes to N workers through DIR.
  std::string farmDir;
  int farmWorkers = 0;
  double farmTimeout = 0.0;
};

// FNV-1a (64-bit) over everything the bake reads from a scene: geometry, materials, cutouts, lights, sky,
// cameras and fine volumes (not names, paths or warnings). Equal scenes give equal hashes on any machine.
uint64_t sceneContentHash(const Scene& scene);

// Layout (little-endian, fields one by one): magic "TPSHARD3", u32 stage, u32 index, u32 count, u64 probeCount,
// u64 sceneHash, f64 floor, u64 options bytes + the bytes, u64 K, then K records (u32 probe, f64 acc[27],
// i32 batches, i32 estimated, f64 mean[6], f64 m2[6], f64 achieved, u64 intersectRays, u64 occludedRays,
// f32 guide[128], i32 guideBatches, u32 P, P x (u64 lit-patch voxel key, f64 light), i32 patchBatches),
// then u64 FNV-1a
// of every byte before it. Written atomically (temp + rename); throws std::runtime_error when it cannot be.
void writeShardPart(const std::string& path, const ShardPart& part);

// Reads and checks a part file (magic, sizes, checksum, a known stage, index < count, probe indices <
// probeCount and increasing). Throws InputError naming the file and the problem.
ShardPart readShardPart(const std::string& path);

// Checks that `parts` are one complete set of shards of `stage`: same stage, scene hash, options, shard
// count, probe count and floor (bit for bit), each shard exactly once, no probe in two shards. Throws
// InputError naming the first problem (with the part's path from `paths`).
void checkShardSet(const std::vector<ShardPart>& parts, const std::vector<std::string>& paths,
                   PartStage stage);

// Checks that `part` was made for the same bake as `reference` (scene hash, options, shard count, probe
// count); InputError naming `path` otherwise.
void checkSameBake(const ShardPart& part, const ShardPart& reference, const std::string& path);

}  // namespace tetraprobe::cli
