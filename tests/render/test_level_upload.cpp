// The level upload (vulkan_upload.h) puts the level into device-local buffers through a staging copy: the
// buffers an engine gets are in a DEVICE_LOCAL memory type when the device has one (lavapipe: every type is
// device-local and host-visible), their bytes come from the recorded vkCmdCopyBuffer and not from a host
// mapping of the level's memory, and they read back byte for byte as packLevelBuffers packed them; the
// staged writeLevelSh leaves them as the packing of the relit level. Read back with vkCmdCopyBuffer, so the
// checks hold on a discrete GPU too.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "lookup_scene.h"
#include "point_lookup.h"
#include "tetraprobe/runtime/gpu_layout.h"
#include "tetraprobe/runtime/gpu_tets.h"
#include "tetraprobe/runtime/probe_update.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/start_bricks.h"
#include "tetraprobe/runtime/vulkan_upload.h"
#include "vulkan_context.h"

namespace tetraprobe {
namespace {

using render_detail::CleanupStack;
using render_detail::GpuBuffer;
using render_detail::vkCheck;
using render_detail::VulkanContext;
using test::submitAndWait;

// Every byte of every level buffer, copied on the GPU into host-visible memory and read there.
std::vector<std::vector<char>> readBack(const VulkanContext& ctx, const VulkanLevelBuffers& buffers) {
  CleanupStack cleanup;
  std::vector<GpuBuffer> host;
  for (int i = 0; i < int(kGpuBindingCount); ++i)
    host.push_back(ctx.createBuffer(
        buffers.sizes[i], VK_BUFFER_USAGE_TRANSFER_DST_BIT,
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT, cleanup));
  submitAndWait(ctx, [&](VkCommandBuffer cmd) {
    for (int i = 0; i < int(kGpuBindingCount); ++i) {
      const VkBufferCopy region{0, 0, buffers.sizes[i]};
      vkCmdCopyBuffer(cmd, buffers.buffers[i], host[size_t(i)].buffer, 1, &region);
    }
    VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    toHost.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    toHost.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &toHost, 0,
                         nullptr, 0, nullptr);
  });
  std::vector<std::vector<char>> out;
  for (int i = 0; i < int(kGpuBindingCount); ++i) {
    void* mapped = nullptr;
    vkCheck(vkMapMemory(ctx.device(), host[size_t(i)].memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory");
    const auto* p = static_cast<const char*>(mapped);
    out.emplace_back(p, p + buffers.sizes[i]);
    vkUnmapMemory(ctx.device(), host[size_t(i)].memory);
  }
  return out;
}

bool deviceHasDeviceLocalMemory(VkPhysicalDevice physicalDevice) {
  VkPhysicalDeviceMemoryProperties props;
  vkGetPhysicalDeviceMemoryProperties(physicalDevice, &props);
  for (uint32_t i = 0; i < props.memoryTypeCount; ++i)
    if (props.memoryTypes[i].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) return true;
  return false;
}

// Number of buffers whose read-back bytes differ from the packed ones (each printed).
int countMismatches(const std::vector<std::vector<char>>& got, const PackedLevelBuffers& want) {
  int bad = 0;
  for (int i = 0; i < int(kGpuBindingCount); ++i) {
    const std::vector<char>& w = want.bytes[i];
    if (got[size_t(i)].size() != w.size() || std::memcmp(got[size_t(i)].data(), w.data(), w.size()) != 0) {
      ++bad;
      ADD_FAILURE() << "binding " << i << ": read back " << got[size_t(i)].size() << " bytes, packed "
                    << w.size() << ", contents differ";
    }
  }
  return bad;
}

// The occluded test level (planes and shadow maps): every one of the six buffers holds real data.
Level occludedLevel() {
  Level level = test::makeLevel();
  level.occlusion = test::syntheticOcclusion(level);
  return level;
}

// An engine's upload: recorded into its own command buffer, staging freed after the submission. Before
// the submission the test overwrites the level buffers wherever it can map them (lavapipe); the read-back
// still equals the packed bytes, so they came from the recorded copy and not from a mapping at upload time.
TEST(LevelUpload, RecordedUploadFillsDeviceLocalBuffersThroughTheStagingCopy) {
  const Level level = occludedLevel();
  const ProbeQuery query(level);
  PackedLevelBuffers packed;
  std::string error;
  ASSERT_TRUE(
      packLevelBuffers(level, query.startGrid(), query.outerCells(), query.cellGrid(), packed, &error))
      << error;
  try {
    VulkanContext ctx;
    VulkanLevelBuffers buffers;
    VulkanStagingBuffer staging;
    bool poisoned = false;
    submitAndWait(ctx, [&](VkCommandBuffer cmd) {
      ASSERT_EQ(cmdUploadLevelBuffers(ctx.physicalDevice(), ctx.device(), cmd, level, query.startGrid(),
                                      query.outerCells(), query.cellGrid(),
                                      VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, buffers, staging, &error),
                VK_SUCCESS)
          << error;
      VkDeviceSize total = 0;
      for (int i = 0; i < int(kGpuBindingCount); ++i) {
        EXPECT_EQ(buffers.sizes[i], VkDeviceSize(packed.bytes[i].size())) << "binding " << i;
        total += buffers.sizes[i];
        if (!(buffers.memoryFlags[i] & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)) continue;
        void* mapped = nullptr;
        ASSERT_EQ(vkMapMemory(ctx.device(), buffers.memory[i], 0, VK_WHOLE_SIZE, 0, &mapped), VK_SUCCESS);
        std::memset(mapped, 0xA5, size_t(buffers.sizes[i]));
        vkUnmapMemory(ctx.device(), buffers.memory[i]);
        poisoned = true;
      }
      EXPECT_EQ(buffers.stagedBytes, total) << "every byte of every buffer comes from the staging copy";
      EXPECT_GE(staging.size, total);
      EXPECT_NE(staging.buffer, VK_NULL_HANDLE);
    });
    destroyStagingBuffer(ctx.device(), staging);
    EXPECT_EQ(staging.buffer, VK_NULL_HANDLE);
    if (deviceHasDeviceLocalMemory(ctx.physicalDevice())) {
      EXPECT_TRUE(levelBuffersDeviceLocal(buffers))
          << "the device has device-local memory: " << ctx.deviceName();
    }
    EXPECT_EQ(countMismatches(readBack(ctx, buffers), packed), 0);
    std::printf("%s: level buffers device-local %s, %llu bytes staged, overwritten before the copy: %s\n",
                ctx.deviceName().c_str(), levelBuffersDeviceLocal(buffers) ? "yes" : "no",
                static_cast<unsigned long long>(buffers.stagedBytes), poisoned ? "yes" : "no (not mappable)");
    destroyLevelBuffers(ctx.device(), buffers);
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).find("no Vulkan") != std::string::npos) GTEST_SKIP() << e.what();
    throw;
  }
}

// The submitted convenience gives the same bytes; the staged writeLevelSh of a range of relit probes leaves
// the buffers exactly as the packing of the relit level (only the SH range changes), and a count of 0 or a
// range outside the level writes nothing.
TEST(LevelUpload, StagedShWriteReadsBackAsThePackingOfTheRelitLevel) {
  Level level = occludedLevel();
  const ProbeQuery query(level);
  PackedLevelBuffers before;
  std::string error;
  ASSERT_TRUE(
      packLevelBuffers(level, query.startGrid(), query.outerCells(), query.cellGrid(), before, &error))
      << error;
  try {
    VulkanContext ctx;
    VulkanLevelBuffers buffers;
    ASSERT_EQ(uploadLevelBuffers(ctx.physicalDevice(), ctx.device(), ctx.queue(), ctx.commandPool(), level,
                                 query.startGrid(), query.outerCells(), query.cellGrid(), buffers, &error),
              VK_SUCCESS)
        << error;
    EXPECT_EQ(countMismatches(readBack(ctx, buffers), before), 0);

    // Probes [5, 17) get brighter, bluer light.
    const size_t first = 5, count = 12;
    std::vector<ShRgb> relit(level.sh.begin() + first, level.sh.begin() + first + count);
    for (ShRgb& sh : relit)
      for (glm::vec3& c : sh.c) c *= glm::vec3(1.5f, 1.25f, 3.0f);
    ASSERT_TRUE(setProbeSh(level, first, relit));
    EXPECT_EQ(writeLevelSh(ctx.physicalDevice(), ctx.device(), ctx.queue(), ctx.commandPool(), buffers, level,
                           first, 0, &error),
              VK_SUCCESS);
    EXPECT_EQ(countMismatches(readBack(ctx, buffers), before), 0) << "count 0 writes nothing";
    EXPECT_EQ(writeLevelSh(ctx.physicalDevice(), ctx.device(), ctx.queue(), ctx.commandPool(), buffers, level,
                           level.sh.size() - 1, 2, &error),
              VK_ERROR_INITIALIZATION_FAILED);
    EXPECT_EQ(countMismatches(readBack(ctx, buffers), before), 0) << "a refused range writes nothing";

    ASSERT_EQ(writeLevelSh(ctx.physicalDevice(), ctx.device(), ctx.queue(), ctx.commandPool(), buffers, level,
                           first, count, &error),
              VK_SUCCESS)
        << error;
    PackedLevelBuffers after;
    ASSERT_TRUE(
        packLevelBuffers(level, query.startGrid(), query.outerCells(), query.cellGrid(), after, &error));
    ASSERT_NE(std::memcmp(after.bytes[kGpuBindingProbes].data(), before.bytes[kGpuBindingProbes].data(),
                          before.bytes[kGpuBindingProbes].size()),
              0)
        << "the relight must change the packed probe buffer for the test to bite";
    EXPECT_EQ(countMismatches(readBack(ctx, buffers), after), 0);
    destroyLevelBuffers(ctx.device(), buffers);
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).find("no Vulkan") != std::string::npos) GTEST_SKIP() << e.what();
    throw;
  }
}

// The tets buffer holds the header and every tet's packed record (gpu_tets.h), each unpacking to the level's
// tet, then the zero tail; its size before the padding is gpuTetBytes, what `inspect` and `eval` count.
TEST(LevelUpload, TetBufferHoldsEveryTetPackedAndItsCountedBytes) {
  const Level level = occludedLevel();
  const ProbeQuery query(level);
  std::string error;
  PackedLevelBuffers packed;
  ASSERT_TRUE(
      packLevelBuffers(level, query.startGrid(), query.outerCells(), query.cellGrid(), packed, &error))
      << error;
  const std::vector<char>& bytes = packed.bytes[kGpuBindingTets];
  const size_t counted = gpuTetBytes(level.probes.size(), level.tets.size());
  EXPECT_EQ(bytes.size(), std::max<size_t>(64, (counted + 63) / 64 * 64));
  GpuTetHeader header;
  std::memcpy(&header, bytes.data(), sizeof(header));
  const GpuTetPacking packing = gpuTetPacking(level.probes.size(), level.tets.size());
  EXPECT_EQ(header.vertexBits, packing.vertexBits);
  EXPECT_EQ(header.neighbourBits, packing.neighbourBits);
  EXPECT_EQ(header.strideUints, packing.strideUints);
  ASSERT_EQ(header.count, level.tets.size());
  std::vector<uint32_t> words((bytes.size() - sizeof(header)) / 4);
  std::memcpy(words.data(), bytes.data() + sizeof(header), words.size() * 4);
  for (size_t t = 0; t < level.tets.size(); ++t) {
    const Tet back = unpackGpuTet(words.data() + t * packing.strideUints, packing);
    for (int i = 0; i < 4; ++i) {
      ASSERT_EQ(back.v[i], level.tets[t].v[i]) << "tet " << t;
      ASSERT_EQ(back.n[i], level.tets[t].n[i]) << "tet " << t;
    }
  }
  for (size_t w = level.tets.size() * packing.strideUints; w < words.size(); ++w) EXPECT_EQ(words[w], 0u);
}

// The start bricks' entries are packed at the tets' neighbour width after the hash slots: each unpacks to
// buildStartBricks' start tet, and the buffer holds what startBricksBytes counts (small cells: many bricks).
TEST(LevelUpload, StartBrickEntriesUnpackToTheBricksStartTets) {
  const Level level = occludedLevel();
  const ProbeQuery query(level, 0.5f);
  std::string error;
  PackedLevelBuffers packed;
  ASSERT_TRUE(
      packLevelBuffers(level, query.startGrid(), query.outerCells(), query.cellGrid(), packed, &error))
      << error;
  const StartBricks bricks = buildStartBricks(level, query.startGrid(), query.cellGrid());
  ASSERT_GT(bricks.startTet.size(), 4096u);
  const std::vector<char>& bytes = packed.bytes[kGpuBindingCells];
  const size_t counted = sizeof(GpuCellGridHeader) + startBricksBytes(query.cellGrid(), level.tets.size());
  EXPECT_EQ(bytes.size(), std::max<size_t>(64, (counted + 63) / 64 * 64));
  GpuCellGridHeader header;
  std::memcpy(&header, bytes.data(), sizeof(header));
  const size_t first = sizeof(header) + size_t(header.brickOffset) * 4;
  ASSERT_LE(first, bytes.size());
  std::vector<uint32_t> words((bytes.size() - first) / 4);
  std::memcpy(words.data(), bytes.data() + first, words.size() * 4);
  const uint32_t width = bitsFor(level.tets.size());
  for (size_t e = 0; e < bricks.startTet.size(); ++e)
    ASSERT_EQ(int32_t(getBits(words.data(), uint64_t(e) * width, width)), bricks.startTet[e])
        << "entry " << e;
}

// A level the shader would read out of bounds is refused before anything is created or recorded.
TEST(LevelUpload, InvalidLevelAllocatesNothing) {
  Level level = occludedLevel();
  const ProbeQuery query(level);
  level.tets[3].v[2] = int32_t(level.probes.size());  // one past the last probe
  std::string error;
  PackedLevelBuffers packed;
  EXPECT_FALSE(
      packLevelBuffers(level, query.startGrid(), query.outerCells(), query.cellGrid(), packed, &error));
  EXPECT_NE(error.find("tet 3"), std::string::npos) << error;
  for (const std::vector<char>& b : packed.bytes) EXPECT_TRUE(b.empty());
  try {
    VulkanContext ctx;
    VulkanLevelBuffers buffers;
    buffers.stagedBytes = 1;  // reset on failure
    VulkanStagingBuffer staging;
    submitAndWait(ctx, [&](VkCommandBuffer cmd) {
      EXPECT_EQ(cmdUploadLevelBuffers(ctx.physicalDevice(), ctx.device(), cmd, level, query.startGrid(),
                                      query.outerCells(), query.cellGrid(),
                                      VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, buffers, staging, &error),
                VK_ERROR_INITIALIZATION_FAILED);
    });
    EXPECT_EQ(staging.buffer, VK_NULL_HANDLE);
    EXPECT_EQ(buffers.stagedBytes, 0u);
    for (int i = 0; i < int(kGpuBindingCount); ++i) EXPECT_EQ(buffers.buffers[i], VK_NULL_HANDLE);
    EXPECT_EQ(uploadLevelBuffers(ctx.physicalDevice(), ctx.device(), ctx.queue(), ctx.commandPool(), level,
                                 query.startGrid(), query.outerCells(), query.cellGrid(), buffers, &error),
              VK_ERROR_INITIALIZATION_FAILED);
    EXPECT_EQ(buffers.buffers[kGpuBindingTets], VK_NULL_HANDLE);
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).find("no Vulkan") != std::string::npos) GTEST_SKIP() << e.what();
    throw;
  }
}

}  // namespace
}  // namespace tetraprobe
