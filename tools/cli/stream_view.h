// `render --stream-window N`: the GPU lookup reading a sector pool (runtime/gpu_sector_pool.h) that holds the
// N sectors of a streamed level nearest the view's target, as an engine streaming that level would show it,
// and where its pixels stand against the full level's.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include <glm/vec3.hpp>

#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/gpu_sector_pool.h"
#include "tetraprobe/runtime/streaming.h"

namespace tetraprobe::cli {

struct StreamView {
  StreamingLevel level;  // the pool reads sectors through it
  GpuSectorPool pool;
  size_t window = 0;
};

// Opens `path` (a level with a streaming index: InputError otherwise), sizes a pool for `window` sectors and
// loads the `window` sectors whose cells' centres lie nearest `target` (world frame).
std::unique_ptr<StreamView> openStreamView(const std::string& path, size_t window, const glm::dvec3& target);

struct StreamViewPixels {
  size_t loaded = 0, identical = 0,
         coarse = 0;  // geometry pixels: from loaded sectors, of those equal, the rest
};

// Compares the pool's render with the full level's (same view) pixel by pixel over geometry.
StreamViewPixels compareStreamView(const StreamView& view, const glm::dvec3& origin, const RenderResult& full,
                                   const RenderResult& streamed);

}  // namespace tetraprobe::cli
