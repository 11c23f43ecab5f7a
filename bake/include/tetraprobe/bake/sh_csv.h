// Probe positions with their SH as CSV: the exchange format for SH baked by another tool (an engine's own
// baker) and for exporting a level's probes. Build side.
//
// Format (text, one probe a line):
//   x,y,z,c0r,c0g,c0b,c1r,c1g,c1b,...,c8r,c8g,c8b
// - x,y,z: world position in metres (the level's frame, right-handed).
// - then 27 numbers, coefficient-major (all three channels of coefficient 0, then coefficient 1, ...), the
//   coefficient index being i = l*(l+1)+m (runtime/sh.h: real basis, no Condon-Shortley phase), values are
//   incident radiance projected onto the basis, W/(m^2 sr). L1 data writes zeros for coefficients 4..8.
// - Blank lines and lines starting with '#' are skipped. The first other line may be a header: it is skipped
//   when its first field is not a number. Fields may carry spaces around them.
// - Numbers are finite decimal floating point (C locale). The writer prints positions with 17 significant
//   digits and coefficients with 9, so a write then read gives the same doubles and floats back.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

struct ProbeShTable {
  std::vector<glm::dvec3> positions;  // world, metres
  std::vector<ShRgb> sh;              // one per position
};

inline constexpr const char* kShCsvHeader =
    "x,y,z,c0r,c0g,c0b,c1r,c1g,c1b,c2r,c2g,c2b,c3r,c3g,c3b,c4r,c4g,c4b,c5r,c5g,c5b,c6r,c6g,c6b,c7r,c7g,c7b,"
    "c8r,c8g,c8b";

// Parses CSV text; `source` names it in errors ("FILE:LINE: ..."). Throws InputError for a wrong field count,
// a non-number, NaN or Inf, naming the line. Empty input gives an empty table.
ProbeShTable parseShCsv(const std::string& text, const std::string& source);

// Reads a file with parseShCsv. Throws InputError when it cannot be opened or read.
ProbeShTable readShCsv(const std::string& path);

// The CSV text for `table`: a '#' comment line naming the format, the header line, one probe a line.
// Throws InputError when positions and sh differ in size.
std::string formatShCsv(const ProbeShTable& table);

// Writes formatShCsv(table) to `path` atomically. Throws std::runtime_error when writing fails.
void writeShCsv(const std::string& path, const ProbeShTable& table);

}  // namespace tetraprobe
