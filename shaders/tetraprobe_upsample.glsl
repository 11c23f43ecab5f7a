// tetraprobe_upsample.glsl: the per-pixel lookup at half resolution, upsampled with depth- and normal-aware
// weights (an engine option, not the default). Permissive; needs nothing but GLSL 4.50 (no buffers: the
// engine reads its own G-buffer and calls tetraprobeIrradiance itself).
//
// Contract
// - Pass 1, at ceil(W/2) x ceil(H/2): for each 2x2 block of full-resolution pixels, tetraprobeHalfPick names
//   the block's representative (the first pixel with geometry in the order tetraprobeHalfOffset gives:
//   (0,0), (1,1), (1,0), (0,1)); the pass looks up E there (tetraprobeIrradiance at that pixel's position and
//   normal) and stores E with the pick (k + 1; 0 for a block without geometry).
// - Pass 2, at W x H: a pixel that is its block's representative copies the stored E (exact). Any other takes
//   the weighted mean of the four half-resolution samples around it (its block's and the three next to it on
//   its side), each weighted by tetraprobeUpsampleWeight from the sample's representative pixel (its
//   position and normal read back from the G-buffer); when the weights sum to less than
//   TETRAPROBE_UPSAMPLE_MIN_WEIGHT (no sample on the pixel's own surface: a silhouette, a crease, a thin
//   object) the pixel runs the full lookup itself, so edges stay exact.
// - Irradiance is upsampled, not outgoing radiance: multiply by the pixel's own albedo afterwards.
// - The answer equals the full-resolution lookup exactly at the representatives and the full lookups; in
//   between it interpolates E over a surface, whose error `tetraprobe bench render` and `tetraprobe eval`
//   report against the full-resolution pass (docs/rendering.md, "Half resolution").
#ifndef TETRAPROBE_UPSAMPLE_GLSL
#define TETRAPROBE_UPSAMPLE_GLSL

// Below this sum of weights a pixel is looked up at full resolution.
const float TETRAPROBE_UPSAMPLE_MIN_WEIGHT = 0.05;
// A sample whose representative lies further than this many pixel footprints off the pixel's tangent plane
// is on another surface (weight 0); the weight falls linearly to that distance.
const float TETRAPROBE_UPSAMPLE_PLANE_FOOTPRINTS = 2.0;
// Samples whose luminances spread wider than this ratio straddle a step in the light (an occlusion edge):
// the pixel is looked up at full resolution.
const float TETRAPROBE_UPSAMPLE_MAX_SPREAD = 1.25;
// Normal similarity: max(dot(n, ns), 0) to this power (10 deg: 0.61; 25 deg: 0.04).
const float TETRAPROBE_UPSAMPLE_NORMAL_POWER = 32.0;

// Offset of a block's k-th candidate pixel (k in 0..3) from the block's top-left pixel.
ivec2 tetraprobeHalfOffset(int k) {
  return k == 0 ? ivec2(0, 0) : k == 1 ? ivec2(1, 1) : k == 2 ? ivec2(1, 0) : ivec2(0, 1);
}

// The index k of a block's representative: the first candidate (tetraprobeHalfOffset order) with geometry;
// -1 when none has any. geometry[k] says whether candidate k is inside the image and covered.
int tetraprobeHalfPick(bvec4 geometry) {
  return geometry.x ? 0 : geometry.y ? 1 : geometry.z ? 2 : geometry.w ? 3 : -1;
}

// The index k that full-resolution pixel `px` has among its block's candidates.
int tetraprobeHalfIndexOf(ivec2 px) {
  ivec2 o = px & 1;
  return o.x == o.y ? o.x : (o.x == 1 ? 2 : 3);
}

// Weight of a half-resolution sample whose representative lies at xs with normal ns, `pixels` pixels away,
// for the pixel at x with normal n; `footprint` is the width of one pixel at x (metres: distance to the eye
// x radians per pixel). Positions in any one frame; normals unit length.
float tetraprobeUpsampleWeight(vec3 x, vec3 n, vec3 xs, vec3 ns, float footprint, float pixels) {
  float plane = abs(dot(n, xs - x)) / max(TETRAPROBE_UPSAMPLE_PLANE_FOOTPRINTS * footprint, 1e-20);
  float facing = pow(max(dot(n, ns), 0.0), TETRAPROBE_UPSAMPLE_NORMAL_POWER);
  return max(1.0 - plane, 0.0) * facing / (1.0 + pixels * pixels);
}

#endif  // TETRAPROBE_UPSAMPLE_GLSL
