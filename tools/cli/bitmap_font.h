// A 5x9 bitmap font of printable ASCII, drawn for tetraprobe's raster plots (`eval --plot FILE.png`), so the
// tool writes legible PNG charts with no font file or font library. Cap height 7 rows, descenders 2.
#pragma once

#include <cstdint>

namespace tetraprobe::cli {

inline constexpr int kGlyphW = 5;         // columns of ink per glyph
inline constexpr int kGlyphH = 9;         // rows per glyph: 7 above the baseline, 2 below
inline constexpr int kGlyphBaseline = 7;  // rows above the baseline
inline constexpr int kGlyphAdvance = 6;   // columns from one glyph's left edge to the next

// The kGlyphH rows of character c, top row first; bit (kGlyphW - 1 - x) of a row is column x (bit 4 is the
// leftmost). Characters outside 32..126 get the glyph of '?'. Never null; static storage.
const uint8_t* glyphRows(char c);

}  // namespace tetraprobe::cli
