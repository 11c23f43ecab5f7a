// The stored per-tet occlusion records (docs/occlusion.md): flat, fixed-size, pointer-free (std430-ready).
// Split from occlusion.h so Level (level.h) can hold them; the evaluation lives in occlusion.h.
// Permissive: standard library only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace tetraprobe {

enum OcclusionKind : uint32_t { kOcclusionNone = 0, kOcclusionPlanes = 1, kOcclusionShadowMaps = 2 };

// Per tet, same order as Level::tets. GLSL: uvec2.
// - header bits 0-1: OcclusionKind; bits 2-3: plane count (1..3, planes only); bits 4-31: offset, the index
//   of the tet's first OcclusionPlane (planes) or of its 64-byte block in shadowMaps (shadow maps).
// - cells (planes only, else 0): the probes visible from each cell of the plane arrangement. Cell c has bit k
//   set when the point is on the positive side of plane k (value >= 0); its 4-bit mask is
//   (cells >> 4c) & 15, bit i = probe tet.v[i] visible. Cells 2^count.. are unused (0).
struct TetOcclusion {
  uint32_t header = 0;
  uint32_t cells = 0;

  OcclusionKind kind() const { return OcclusionKind(header & 3u); }
  uint32_t planeCount() const { return (header >> 2) & 3u; }
  uint32_t offset() const { return header >> 4; }
};
static_assert(sizeof(TetOcclusion) == 8, "TetOcclusion is a std430 uvec2");

inline constexpr uint32_t kOcclusionMaxOffset = (1u << 28) - 1u;

inline TetOcclusion makeTetOcclusion(OcclusionKind kind, uint32_t planeCount, uint32_t offset,
                                     uint32_t cells) {
  return TetOcclusion{uint32_t(kind) | (planeCount & 3u) << 2 | offset << 4, cells};
}

// A splitting plane in the tet's barycentric frame, in snorm16: value(i) = c[i] / 32767 is the signed
// distance of probe tet.v[i] to the plane divided by the largest of the four absolute distances (so
// max |value(i)| = 1, up to the quantization). Its value at a point with weights w is sum_i value(i) w_i: the
// signed distance in units of that largest distance. 16 bits hold it to 1.5e-5 of the tet's size, far below
// the blend's half-width kOcclusionPlaneFalloff (0.02). GLSL: uvec2, c[0] | c[1] << 16 and c[2] | c[3] << 16.
struct OcclusionPlane {
  int16_t c[4] = {0, 0, 0, 0};

  float value(int i) const { return float(c[i]) * kOcclusionPlaneUnit; }
  // The zero plane: no plane (every probe on it); never stored.
  bool isZero() const { return c[0] == 0 && c[1] == 0 && c[2] == 0 && c[3] == 0; }
  static constexpr float kOcclusionPlaneUnit = 1.0f / 32767.0f;
};
static_assert(sizeof(OcclusionPlane) == 8, "OcclusionPlane is a std430 uvec2");

// The plane with coefficients d[0..3] scaled so the largest |d[i]| is 1, rounded to snorm16 (nearest). A
// zero or non-finite d gives the zero plane (which validateLevel refuses).
OcclusionPlane makeOcclusionPlane(double d0, double d1, double d2, double d3);

// Shadow maps: 4 probes x 16 bytes, probe slot i at block * 64 + 16 i. The face opposite probe tet.v[i] is
// split 4x4 into 16 sub-triangles (shadowMapCell); byte shadowMapVertex(a, b) (15 used, byte 15 = 255) holds
// the depth at lattice vertex (u, v) = (a/4, b/4), a + b <= 4: the fraction f of the way from the probe to
// that face point at which the first geometry is met, as round(254 f) (0..254), or 255 when nothing is met
// before the face. Inside a sub-triangle the depth is interpolated from its three corners harmonically,
// 1/d = sum_k b_k / d_k (a no-hit corner counts as d = 1): exact for any planar occluder met by all three
// corner rays, where one value per sub-triangle (the centre ray) misjudges every point off the centre.
inline constexpr int kShadowMapTexels = 16;
inline constexpr int kShadowMapBlockBytes = 4 * kShadowMapTexels;
inline constexpr uint8_t kShadowMapNoHit = 255;
inline constexpr float kShadowMapScale = 254.0f;
inline constexpr int kShadowMapLatticeVertices = 15;
inline constexpr int shadowMapVertex(int a, int b) {
  return b * 5 - b * (b - 1) / 2 + a;
}  // a + b <= 4
static_assert(shadowMapVertex(0, 4) == kShadowMapLatticeVertices - 1, "15 lattice vertices in 16 bytes");

// The occlusion data of a level. `tets` empty means the level has none: nothing stored, nothing evaluated
// (every probe visible). Otherwise tets.size() == level.tets.size().
struct LevelOcclusion {
  std::vector<TetOcclusion> tets;
  std::vector<OcclusionPlane> planes;
  std::vector<uint8_t> shadowMaps;  // multiple of 64 bytes

  bool empty() const { return tets.empty(); }
  size_t bytes() const {
    return tets.size() * sizeof(TetOcclusion) + planes.size() * sizeof(OcclusionPlane) + shadowMaps.size();
  }
};

}  // namespace tetraprobe
