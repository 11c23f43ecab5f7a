// The GPU half of engine_integration (gpu_level.cpp): the level's buffers uploaded and relit with the
// engine's own queue and command buffers.
#pragma once

#include <tetraprobe/runtime/level.h>
#include <tetraprobe/runtime/query.h>

// Uploads `level` (with `query`'s acceleration data) to the first Vulkan device, prints the buffers the
// engine then owns, relights part of the level in place (setProbeSh on `level`, cmdUpdateLevelSh on the GPU)
// and checks the GPU copy against the relit level byte for byte. Returns true on success, and when there is
// no Vulkan device (it says so and skips); false when a check or a Vulkan call fails.
bool runGpuLevel(tetraprobe::Level& level, const tetraprobe::ProbeQuery& query);
