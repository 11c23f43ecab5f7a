// Small text helpers for the build side's line-based input files (probe CSV, SH CSV).
#pragma once

#include <string_view>

namespace tetraprobe {

// `s` without leading and trailing white space (space, tab, CR, LF, VT, FF).
std::string_view trimWhitespace(std::string_view s);

// Parses one whole field (surrounding white space allowed, an optional leading '+') as a finite double.
// Returns false for anything else: empty, trailing text, NaN, Inf, out of range.
bool parseFiniteField(std::string_view field, double& out);

}  // namespace tetraprobe
