// The streamed half of engine_integration (gpu_streaming.cpp): a camera's loop over a streamed level with its
// sectors loaded into and evicted from a fixed-size GPU pool within a memory budget.
#pragma once

#include <string>

// Opens the streamed level at `path`, sizes the pool to `budgetShare` of the full level's GPU bytes, and
// flies `frames` frames, printing a line per frame. Returns true on success and when there is no Vulkan
// device (it says so and skips); false when a check, a load or a Vulkan call fails.
bool runGpuStreaming(const std::string& path, double budgetShare, int frames);
