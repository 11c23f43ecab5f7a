// The point location's tolerances and step bounds: the CPU query (runtime/src/query.cpp, outer_cells.cpp)
// uses them, and the GLSL lookup (shaders/tetraprobe.glsl, TETRAPROBE_* macros of the same meaning) mirrors
// them; tests/runtime/test_glsl_layout.cpp fails when a GLSL value differs from the one here. Permissive:
// standard library only.
#pragma once

namespace tetraprobe {

// A barycentric weight >= -kLookupInsideEps counts as inside (Location::inside). GLSL: TETRAPROBE_INSIDE_EPS.
inline constexpr double kLookupInsideEps = 1e-6;
// A walk that cycles is answered by its best tet if that tet holds the point within this (smallest weight
// >= -kLookupCycleAcceptEps). GLSL: TETRAPROBE_CYCLE_ACCEPT_EPS.
inline constexpr double kLookupCycleAcceptEps = 1e-4;
// A walk from a caller's hint tet takes at most this many steps before starting again from the start grid.
// GLSL: TETRAPROBE_MAX_HINT_STEPS.
inline constexpr int kLookupMaxHintSteps = 256;
// An outer-cell walk takes at most this many steps before the scan of every outer cell.
// GLSL: TETRAPROBE_MAX_OUTER_STEPS.
inline constexpr int kLookupMaxOuterSteps = 1024;
// Outer cells' root solver: roots beyond kLookupOuterMaxT * scale are not looked for (CPU and GPU alike).
// GLSL: TETRAPROBE_OUTER_MAX_T.
inline constexpr double kLookupOuterMaxT = 1e4;
// The same solver's thresholds in float on the GPU (the CPU solves in double with 1e-13 and 1e-12): a term
// below this fraction of the others is dropped; roots within this fraction of the scale below 0 count as 0.
// GLSL: TETRAPROBE_OUTER_NEGLIGIBLE, TETRAPROBE_OUTER_ZERO_ROOT.
inline constexpr double kGpuOuterNegligible = 1e-6;
inline constexpr double kGpuOuterZeroRoot = 1e-6;

}  // namespace tetraprobe
