// One probe of the bake, shared by bakeProbes and the ray recorder (bench_rays.cpp). Internal to the bake
// module.
#pragma once

#include <cstddef>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/bake.h"

namespace tetraprobe::bake_detail {

// The SH of one probe at `probe` with bake index `index` (keys its random streams), before any order
// truncation. Rays go through the calling thread's RayTap, if one is installed.
ShRgb bakeProbe(const SceneTracer& tracer, const glm::vec3& probe, size_t index, const BakeOptions& options);

// Throws InputError for options bakeProbes rejects (samples, bounces, SH order).
void validateBakeOptions(const BakeOptions& options);

}  // namespace tetraprobe::bake_detail
