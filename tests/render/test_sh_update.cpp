// Run-time SH updates (probe_update.h, vulkan_upload.h's writeLevelSh / cmdUpdateLevelSh) relight a level on
// the CPU and on the GPU exactly as a level freshly built with the new SH: the test uploads a level once,
// replaces all or part of its SH in place, and compares the GPU lookup (shaders/tetraprobe.glsl through
// point_lookup.comp, on lavapipe) and the CPU query with those of a level built from scratch with the same
// probes and the new SH.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "point_lookup.comp.h"
#include "tetraprobe/runtime/probe_update.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/vulkan_upload.h"
#include "tetraprobe/tetra/tetrahedralize.h"
#include "vulkan_context.h"

namespace tetraprobe {
namespace {

using render_detail::CleanupStack;
using render_detail::GpuBuffer;
using render_detail::vkCheck;
using render_detail::VulkanContext;

const glm::dvec3 kOrigin(1000.0, -20.0, 500.0);  // far from the world origin, as a real level may be

// The probes: 5x3x5 on a 1 m grid over local [0,4]x[0,2]x[0,4], jittered so no four are cospherical, in
// z-major order (probes [15 z, 15 z + 15) form the layer z).
std::vector<glm::dvec3> probePositions() {
  std::vector<glm::dvec3> world;
  for (int z = 0; z < 5; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x)
        world.push_back(kOrigin + glm::dvec3(x + 0.07 * std::sin(1.3 * x + 2.1 * y + 0.7 * z),
                                             y + 0.05 * std::cos(0.9 * x + 1.7 * z),
                                             z + 0.06 * std::sin(2.3 * y + 0.4 * x)));
  return world;
}

// "Daylight": a smooth field, L00 dominant so E stays positive (relative errors are meaningful).
ShRgb daylight(const glm::vec3& p) {
  ShRgb sh;
  sh.c[0] = glm::vec3(2.0f + 0.4f * p.x, 1.5f + 0.3f * p.y, 1.0f + 0.2f * p.z);
  sh.c[1] = glm::vec3(0.2f * p.y, -0.1f, 0.05f * p.x);
  sh.c[2] = glm::vec3(-0.15f, 0.1f * p.z, 0.2f);
  sh.c[3] = glm::vec3(0.1f * p.x, 0.05f, -0.1f * p.z);
  for (int i = 4; i < 9; ++i)
    sh.c[size_t(i)] = glm::vec3(0.03f * float(i - 6) + 0.01f * p.x, 0.02f * p.y, -0.02f * float(i - 5));
  return sh;
}

// "A lamp switched on": warmer, brighter towards +x, the L1 direction turned 90 degrees about y, L2 flipped.
ShRgb lamp(const glm::vec3& p) {
  const ShRgb d = daylight(p);
  ShRgb sh;
  const glm::vec3 tint(1.6f, 0.9f, 0.4f);
  sh.c[0] = d.c[0] * tint * (1.0f + 0.3f * p.x);
  sh.c[1] = d.c[1] * tint;
  sh.c[2] = -d.c[3] * tint;  // (x, z) -> (z, -x)
  sh.c[3] = d.c[2] * tint;
  for (int i = 4; i < 9; ++i) sh.c[size_t(i)] = -0.5f * d.c[size_t(i)];
  return sh;
}

// Plane occlusion on three tets in four (random planes and visible sets), so the update is checked with the
// occluded blend too. It depends on the tets only, as real occlusion depends on tets and geometry.
LevelOcclusion planeOcclusion(size_t tets) {
  LevelOcclusion occ;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (size_t t = 0; t < tets; ++t) {
    if (t % 4 == 3) {
      occ.tets.push_back(makeTetOcclusion(kOcclusionNone, 0, 0, 0));
      continue;
    }
    const uint32_t count = uint32_t(t % 3) + 1;
    uint32_t cells = 0;
    for (uint32_t c = 0; c < (1u << count); ++c) cells |= (1u + uint32_t(rng()) % 15u) << (4 * c);
    occ.tets.push_back(makeTetOcclusion(kOcclusionPlanes, count, uint32_t(occ.planes.size()), cells));
    for (uint32_t k = 0; k < count; ++k) {
      OcclusionPlane p;
      float m = 0.0f;
      for (float& c : p.c) m = std::max(m, std::abs(c = u(rng)));
      for (float& c : p.c) c /= m;
      occ.planes.push_back(p);
    }
  }
  return occ;
}

// A level built from scratch: tetrahedralized, occluded, with probe p's SH = sh(p).
Level buildLevel(const std::function<ShRgb(size_t, const glm::vec3&)>& sh) {
  const std::vector<glm::dvec3> world = probePositions();
  Level level;
  level.origin = kOrigin;
  for (size_t p = 0; p < world.size(); ++p) {
    level.probes.emplace_back(world[p] - kOrigin);
    level.sh.push_back(sh(p, level.probes.back()));
  }
  level.tets = buildTetRecords(world, tetrahedralizeDelaunay(world), kOrigin);
  level.occlusion = planeOcclusion(level.tets.size());
  return level;
}

struct PointNormal {
  float position[4];
  float normal[4];
};

// Points in and around the probe hull (local [-1,5]x[-1,3]x[-1,5]) with random unit normals.
std::vector<PointNormal> makePoints(size_t n) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), s(-1.0f, 1.0f);
  std::vector<PointNormal> pts(n);
  for (PointNormal& q : pts) {
    const glm::vec3 x(-1.0f + 6.0f * u(rng), -1.0f + 4.0f * u(rng), -1.0f + 6.0f * u(rng));
    const glm::vec3 nrm = glm::normalize(glm::vec3(s(rng), s(rng), s(rng)) + glm::vec3(1e-3f));
    for (int a = 0; a < 3; ++a) q.position[a] = x[a], q.normal[a] = nrm[a];
    q.position[3] = q.normal[3] = 0.0f;
  }
  return pts;
}

std::vector<glm::vec3> cpuIrradiance(const ProbeQuery& q, const std::vector<PointNormal>& pts) {
  std::vector<glm::vec3> out;
  for (const PointNormal& p : pts)
    out.push_back(q.irradiance(q.level().origin + glm::dvec3(p.position[0], p.position[1], p.position[2]),
                               glm::vec3(p.normal[0], p.normal[1], p.normal[2])));
  return out;
}

// point_lookup.comp over a fixed point list: set 0 = a level's six buffers, set 1 = points and results.
class PointLookup {
 public:
  explicit PointLookup(const std::vector<PointNormal>& pts) : count_(uint32_t(pts.size())) {
    const VkDevice dev = ctx_.device();
    VkDescriptorSetLayoutBinding levelBindings[kGpuBindingCount];
    levelDescriptorBindings(VK_SHADER_STAGE_COMPUTE_BIT, 0, levelBindings);
    VkDescriptorSetLayoutBinding ioBindings[2] = {};
    for (uint32_t i = 0; i < 2; ++i)
      ioBindings[i] = {i, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
    setLayouts_[0] = setLayout(levelBindings, kGpuBindingCount);
    setLayouts_[1] = setLayout(ioBindings, 2);

    const VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t)};
    VkPipelineLayoutCreateInfo pli{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pli.setLayoutCount = 2;
    pli.pSetLayouts = setLayouts_;
    pli.pushConstantRangeCount = 1;
    pli.pPushConstantRanges = &push;
    vkCheck(vkCreatePipelineLayout(dev, &pli, nullptr, &layout_), "vkCreatePipelineLayout");
    cleanup_.push([dev, l = layout_] { vkDestroyPipelineLayout(dev, l, nullptr); });
    VkShaderModuleCreateInfo smi{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    smi.codeSize = sizeof(kSpirv_point_lookup_comp);
    smi.pCode = kSpirv_point_lookup_comp;
    VkShaderModule module;
    vkCheck(vkCreateShaderModule(dev, &smi, nullptr, &module), "vkCreateShaderModule");
    cleanup_.push([dev, module] { vkDestroyShaderModule(dev, module, nullptr); });
    VkComputePipelineCreateInfo cpi{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    cpi.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    cpi.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    cpi.stage.module = module;
    cpi.stage.pName = "main";
    cpi.layout = layout_;
    vkCheck(vkCreateComputePipelines(dev, VK_NULL_HANDLE, 1, &cpi, nullptr, &pipeline_),
            "vkCreateComputePipelines");
    cleanup_.push([dev, p = pipeline_] { vkDestroyPipeline(dev, p, nullptr); });

    const VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 64};
    VkDescriptorPoolCreateInfo dpi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dpi.maxSets = 8;
    dpi.poolSizeCount = 1;
    dpi.pPoolSizes = &size;
    vkCheck(vkCreateDescriptorPool(dev, &dpi, nullptr, &pool_), "vkCreateDescriptorPool");
    cleanup_.push([dev, p = pool_] { vkDestroyDescriptorPool(dev, p, nullptr); });

    const VkMemoryPropertyFlags host =
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    const VkDeviceSize bytes = sizeof(PointNormal) * pts.size();
    points_ = ctx_.createBuffer(bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, host, cleanup_);
    results_ = ctx_.createBuffer(16 * pts.size(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, host, cleanup_);
    void* mapped = nullptr;
    vkCheck(vkMapMemory(dev, points_.memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory");
    std::memcpy(mapped, pts.data(), size_t(bytes));
    vkUnmapMemory(dev, points_.memory);
    ioSet_ = allocateSet(setLayouts_[1]);
    VkDescriptorBufferInfo infos[2] = {{points_.buffer, 0, VK_WHOLE_SIZE},
                                       {results_.buffer, 0, VK_WHOLE_SIZE}};
    VkWriteDescriptorSet writes[2];
    for (uint32_t i = 0; i < 2; ++i) {
      writes[i] = VkWriteDescriptorSet{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      writes[i].dstSet = ioSet_;
      writes[i].dstBinding = i;
      writes[i].descriptorCount = 1;
      writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      writes[i].pBufferInfo = &infos[i];
    }
    vkUpdateDescriptorSets(dev, 2, writes, 0, nullptr);
  }
  ~PointLookup() {
    for (VulkanLevelBuffers& b : uploads_) destroyLevelBuffers(ctx_.device(), b);
    cleanup_.run();
  }

  VkDevice device() const { return ctx_.device(); }

  // Uploads `level` (with `query`'s acceleration data); returns its index for run().
  size_t upload(const Level& level, const ProbeQuery& query) {
    VulkanLevelBuffers b;
    std::string error;
    const VkResult r = uploadLevelBuffers(ctx_.physicalDevice(), ctx_.device(), level, query.startGrid(),
                                          query.outerCells(), query.cellGrid(), b, &error);
    if (r != VK_SUCCESS) throw std::runtime_error("upload: " + error);
    uploads_.push_back(b);
    sets_.push_back(allocateSet(setLayouts_[0]));
    writeLevelDescriptors(ctx_.device(), sets_.back(), 0, b);
    return uploads_.size() - 1;
  }
  const VulkanLevelBuffers& buffers(size_t i) const { return uploads_[i]; }

  // One submission: `record` (if any: e.g. an SH update), then the lookup of every point against upload i.
  std::vector<glm::vec3> run(size_t i, const std::function<void(VkCommandBuffer)>& record = {}) {
    const VkDevice dev = ctx_.device();
    VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cai.commandPool = ctx_.commandPool();
    cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cai.commandBufferCount = 1;
    VkCommandBuffer cmd;
    vkCheck(vkAllocateCommandBuffers(dev, &cai, &cmd), "vkAllocateCommandBuffers");
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    vkCheck(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
    if (record) record(cmd);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
    const VkDescriptorSet sets[2] = {sets_[i], ioSet_};
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 2, sets, 0, nullptr);
    vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t), &count_);
    vkCmdDispatch(cmd, (count_ + 63) / 64, 1, 1);
    VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    toHost.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    toHost.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &toHost,
                         0, nullptr, 0, nullptr);
    vkCheck(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    vkCheck(vkCreateFence(dev, &fci, nullptr, &fence), "vkCreateFence");
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    vkCheck(vkQueueSubmit(ctx_.queue(), 1, &submit, fence), "vkQueueSubmit");
    vkCheck(vkWaitForFences(dev, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
    vkDestroyFence(dev, fence, nullptr);
    vkFreeCommandBuffers(dev, ctx_.commandPool(), 1, &cmd);
    std::vector<glm::vec3> out(count_);
    void* mapped = nullptr;
    vkCheck(vkMapMemory(dev, results_.memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory");
    const auto* f = static_cast<const float*>(mapped);
    for (size_t k = 0; k < count_; ++k) out[k] = glm::vec3(f[4 * k], f[4 * k + 1], f[4 * k + 2]);
    vkUnmapMemory(dev, results_.memory);
    return out;
  }

 private:
  VkDescriptorSetLayout setLayout(const VkDescriptorSetLayoutBinding* b, uint32_t n) {
    VkDescriptorSetLayoutCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    info.bindingCount = n;
    info.pBindings = b;
    VkDescriptorSetLayout l;
    const VkDevice dev = ctx_.device();
    vkCheck(vkCreateDescriptorSetLayout(dev, &info, nullptr, &l), "vkCreateDescriptorSetLayout");
    cleanup_.push([dev, l] { vkDestroyDescriptorSetLayout(dev, l, nullptr); });
    return l;
  }
  VkDescriptorSet allocateSet(VkDescriptorSetLayout l) {
    VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    info.descriptorPool = pool_;
    info.descriptorSetCount = 1;
    info.pSetLayouts = &l;
    VkDescriptorSet s;
    vkCheck(vkAllocateDescriptorSets(ctx_.device(), &info, &s), "vkAllocateDescriptorSets");
    return s;
  }

  VulkanContext ctx_;
  CleanupStack cleanup_;
  uint32_t count_;
  VkDescriptorSetLayout setLayouts_[2] = {};
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  GpuBuffer points_, results_;
  VkDescriptorSet ioSet_ = VK_NULL_HANDLE;
  std::vector<VulkanLevelBuffers> uploads_;
  std::vector<VkDescriptorSet> sets_;
};

// Largest relative difference per channel (denominator at least 1e-6 W/m^2).
double worstRelative(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i)
    for (int c = 0; c < 3; ++c)
      worst =
          std::max(worst, std::abs(double(a[i][c]) - b[i][c]) / std::max(std::abs(double(b[i][c])), 1e-6));
  return worst;
}

size_t countDifferent(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
  return n;
}

// The whole relight, in the order an engine does it: upload a level lit by daylight; switch the lamp on for
// every probe (setProbeSh + writeLevelSh while the GPU is idle); then relight one layer of probes in a
// command buffer that also renders (cmdUpdateLevelSh before the lookup). After each step the CPU query of the
// updated level equals, bit for bit, that of a level built from scratch with the same SH (same tets: the
// tetrahedralization does not look at the SH), and the GPU lookup of the updated buffers equals, bit for bit,
// the lookup of a fresh upload of that level, and the CPU within 1e-4 relative (the tolerance of
// GpuLookup.MatchesCpuQueryPerPixel, which explains it). Each update must change the answers (the test can
// fail), and the partial one only near the relit layer.
TEST(ShUpdate, RelitLevelMatchesFreshLevelOnCpuAndGpu) {
  const std::vector<PointNormal> pts = makePoints(4096);
  Level level = buildLevel([](size_t, const glm::vec3& p) { return daylight(p); });
  const ProbeQuery query(level);
  std::vector<glm::vec3> before;
  try {
    PointLookup gpu(pts);
    const size_t live = gpu.upload(level, query);
    before = gpu.run(live);
    EXPECT_LT(worstRelative(before, cpuIrradiance(query, pts)), 1e-4) << "GPU against CPU before any update";

    // 1. Every probe, through a mapping.
    const Level lampLevel = buildLevel([](size_t, const glm::vec3& p) { return lamp(p); });
    ASSERT_EQ(lampLevel.tets.size(), level.tets.size());
    ASSERT_EQ(std::memcmp(lampLevel.tets.data(), level.tets.data(), sizeof(Tet) * level.tets.size()), 0)
        << "a fresh build of the same probes must give the same tets";
    const ProbeQuery lampQuery(lampLevel);
    ASSERT_TRUE(setProbeSh(level, 0, lampLevel.sh));
    std::string error;
    ASSERT_EQ(writeLevelSh(gpu.device(), gpu.buffers(live), level, 0, level.sh.size(), &error), VK_SUCCESS)
        << error;
    const std::vector<glm::vec3> cpuLamp = cpuIrradiance(lampQuery, pts);
    EXPECT_EQ(countDifferent(cpuIrradiance(query, pts), cpuLamp), 0u) << "CPU: relit level against fresh";
    const std::vector<glm::vec3> relit = gpu.run(live);
    const std::vector<glm::vec3> freshLamp = gpu.run(gpu.upload(lampLevel, lampQuery));
    EXPECT_EQ(countDifferent(relit, freshLamp), 0u) << "GPU: updated buffers against a fresh upload";
    EXPECT_LT(worstRelative(relit, cpuLamp), 1e-4) << "GPU against CPU after the update";
    EXPECT_GT(countDifferent(relit, before), pts.size() * 99 / 100) << "the lamp must change the answers";

    // 2. The layer z = 2 (probes [30, 45)) back to daylight, recorded in the command buffer of the lookup.
    const size_t first = 30, count = 15;
    const auto mixed = [&](size_t p, const glm::vec3& x) {
      return p >= first && p < first + count ? daylight(x) : lamp(x);
    };
    const Level mixedLevel = buildLevel(mixed);
    const ProbeQuery mixedQuery(mixedLevel);
    ASSERT_TRUE(setProbeSh(level, first, {mixedLevel.sh.data() + first, count}));
    bool recorded = false;
    const std::vector<glm::vec3> partial = gpu.run(live, [&](VkCommandBuffer cmd) {
      recorded = cmdUpdateLevelSh(cmd, gpu.buffers(live), level, first, count,
                                  VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, &error);
    });
    ASSERT_TRUE(recorded) << error;
    const std::vector<glm::vec3> cpuMixed = cpuIrradiance(mixedQuery, pts);
    EXPECT_EQ(countDifferent(cpuIrradiance(query, pts), cpuMixed), 0u) << "CPU: partly relit against fresh";
    EXPECT_EQ(countDifferent(partial, gpu.run(gpu.upload(mixedLevel, mixedQuery))), 0u)
        << "GPU: partly updated buffers against a fresh upload";
    EXPECT_LT(worstRelative(partial, cpuMixed), 1e-4);
    const size_t changed = countDifferent(partial, relit);
    EXPECT_GT(changed, pts.size() / 10) << "points near layer z = 2 must change";
    EXPECT_LT(changed, pts.size() * 9 / 10) << "points far from layer z = 2 must not";
    std::printf("partial update of %zu probes changed %zu of %zu points\n", count, changed, pts.size());

    // 3. Out-of-range and mismatched requests are refused and leave the buffers as they were.
    EXPECT_EQ(writeLevelSh(gpu.device(), gpu.buffers(live), level, level.sh.size(), 1, &error),
              VK_ERROR_INITIALIZATION_FAILED);
    EXPECT_NE(error.find("outside"), std::string::npos) << error;
    EXPECT_EQ(writeLevelSh(gpu.device(), gpu.buffers(live), level, 1, level.sh.size(), &error),
              VK_ERROR_INITIALIZATION_FAILED);
    Level bigger = level;
    for (int k = 0; k < 200; ++k) {
      bigger.probes.push_back(glm::vec3(0.0f));
      bigger.sh.push_back(ShRgb{});
    }
    EXPECT_EQ(writeLevelSh(gpu.device(), gpu.buffers(live), bigger, 0, 1, &error),
              VK_ERROR_INITIALIZATION_FAILED)
        << "a level with more probes than the buffer was uploaded with";
    EXPECT_NE(error.find("cannot hold"), std::string::npos) << error;
    recorded = true;
    EXPECT_EQ(countDifferent(gpu.run(live,
                                     [&](VkCommandBuffer cmd) {
                                       recorded = cmdUpdateLevelSh(
                                           cmd, gpu.buffers(live), level, level.sh.size() - 1, 2,
                                           VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, &error);
                                     }),
                             partial),
              0u);
    EXPECT_FALSE(recorded);
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).find("no Vulkan") != std::string::npos) GTEST_SKIP() << e.what();
    throw;
  }
}

}  // namespace
}  // namespace tetraprobe
