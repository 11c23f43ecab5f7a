// The engine-facing include compiles outside the renderer (a fragment shader) and its binding macros move
// the five buffers where the engine asks.
#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <set>
#include <utility>

#include "engine_include.frag.h"
#include "tetraprobe/runtime/gpu_layout.h"

namespace tetraprobe {
namespace {

// (set, binding) of every decorated variable in a SPIR-V module.
std::set<std::pair<uint32_t, uint32_t>> descriptorSlots(const uint32_t* words, size_t count) {
  constexpr uint32_t kOpDecorate = 71, kBinding = 33, kDescriptorSet = 34;
  std::map<uint32_t, uint32_t> set, binding;
  for (size_t i = 5; i < count;) {  // 5-word header
    const uint32_t op = words[i] & 0xffff, len = words[i] >> 16;
    if (len == 0) break;
    if (op == kOpDecorate && len >= 4) {
      if (words[i + 2] == kDescriptorSet) set[words[i + 1]] = words[i + 3];
      if (words[i + 2] == kBinding) binding[words[i + 1]] = words[i + 3];
    }
    i += len;
  }
  std::set<std::pair<uint32_t, uint32_t>> slots;
  for (const auto& [id, b] : binding) slots.insert({set.count(id) ? set[id] : 0u, b});
  return slots;
}

// TETRAPROBE_SET 2 / TETRAPROBE_BINDING 5 put tets, SH, grid, outer cells, cell grid and occlusion at set 2,
// bindings 5..10 (the layout levelDescriptorBindings(stages, 5, ...) describes), and nothing else.
TEST(GlslInclude, BindingMacrosMoveTheBuffers) {
  const auto slots = descriptorSlots(kSpirv_engine_include_frag, sizeof(kSpirv_engine_include_frag) / 4);
  const std::set<std::pair<uint32_t, uint32_t>> expected = {
      {2u, 5u + kGpuBindingTets},       {2u, 5u + kGpuBindingProbes}, {2u, 5u + kGpuBindingGrid},
      {2u, 5u + kGpuBindingOuterCells}, {2u, 5u + kGpuBindingCells},  {2u, 5u + kGpuBindingOcclusion}};
  EXPECT_EQ(slots, expected);
}

}  // namespace
}  // namespace tetraprobe
