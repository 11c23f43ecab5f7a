// The GPU half of engine_integration (gpu_level.cpp): the level's buffers uploaded and relit with the
// engine's own queue and command buffers.
#pragma once

#include <vector>

#include <glm/vec3.hpp>

#include <tetraprobe/runtime/level.h>
#include <tetraprobe/runtime/query.h>

// Uploads `level` (with `query`'s acceleration data) to the first Vulkan device, prints the buffers the
// engine then owns, shades the surface points (world positions, unit normals) in the engine's lighting pass
// (surface_lighting.h: tetraprobe.glsl per pixel), relights part of the level in place (setProbeSh on
// `level`, cmdUpdateLevelSh on the GPU) and shades them again. Checks: each pass's per-pixel answers equal
// ProbeQuery::irradiance of the level as it then is, within 1e-4 relative per channel (float on the GPU,
// double on the CPU); the GPU copy of the probes equals the relit level byte for byte. Returns true on
// success, and when there is no Vulkan device (it says so and skips); false when a check or a Vulkan call
// fails.
bool runGpuLevel(tetraprobe::Level& level, const tetraprobe::ProbeQuery& query,
                 const std::vector<glm::dvec3>& points, const std::vector<glm::vec3>& normals);
