// Automatic probe placement. Build side.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace tetraprobe {

// A regular grid at `spacing` metres covering [lo, hi] (inclusive, centred so the margins are equal), in
// x-fastest order: floor(extent / spacing) + 1 points per axis (an extent that is an exact multiple of the
// spacing, to 1e-9 relative, puts points on both faces), all inside the box. Throws InputError for a
// non-positive or non-finite spacing, non-finite corners, hi < lo on an axis, or when the grid would exceed
// `maxProbes` points (checked before allocating).
std::vector<glm::dvec3> placeGridProbes(const glm::dvec3& lo, const glm::dvec3& hi, double spacing,
                                        size_t maxProbes = 5'000'000);

// Reads user probes from a CSV file: one `x,y,z` a line (world metres); blank lines and lines starting with
// '#' are skipped. Throws InputError naming the file and line for anything else (non-numbers, NaN, Inf).
std::vector<glm::dvec3> readProbeCsv(const std::string& path);

}  // namespace tetraprobe
