// tetraprobe_sh.glsl: real SH L2 basis and cosine-convolved irradiance, the GLSL twin of runtime/sh.h. Permissive.
//
// Same conventions as tetraprobe/runtime/sh.h: real basis without the Condon-Shortley phase, index
// l*(l+1)+m (0:1 1:y 2:z 3:x 4:xy 5:yz 6:3z^2-1 7:xz 8:x^2-y^2), coefficients are incident radiance in
// W/(m^2 sr), E(n) = sum_i A_l(i) L_i Y_i(n) in W/m^2 with A_0 = pi, A_1 = 2pi/3, A_2 = pi/4.
// The constants are the double literals of sh.h (rounded to float exactly as the CPU's float(k) is) and every
// product is written in the CPU's order and marked `precise`, so CPU and GPU differ only by rounding.
#ifndef TETRAPROBE_SH_GLSL
#define TETRAPROBE_SH_GLSL

const float kTetraprobeY00 = 0.28209479177387814;  // 1 / (2 sqrt(pi))
const float kTetraprobeY1 = 0.4886025119029199;    // sqrt(3 / (4 pi))
const float kTetraprobeY2n2 = 1.0925484305920792;  // sqrt(15 / pi) / 2
const float kTetraprobeY20 = 0.31539156525252005;  // sqrt(5 / pi) / 4
const float kTetraprobeY22 = 0.5462742152960396;   // sqrt(15 / pi) / 4
const float kTetraprobeA0 = 3.141592653589793;     // pi
const float kTetraprobeA1 = 2.0943951023931953;    // 2 pi / 3
const float kTetraprobeA2 = 0.7853981633974483;    // pi / 4

// The 9 basis functions at unit direction d (writes each product in sh.h's order; no contraction).
#define TETRAPROBE_SH_BASIS(y, d)                  \
  y[0] = kTetraprobeY00;                           \
  y[1] = kTetraprobeY1 * d.y;                      \
  y[2] = kTetraprobeY1 * d.z;                      \
  y[3] = kTetraprobeY1 * d.x;                      \
  y[4] = kTetraprobeY2n2 * d.x * d.y;              \
  y[5] = kTetraprobeY2n2 * d.y * d.z;              \
  y[6] = kTetraprobeY20 * (3.0 * d.z * d.z - 1.0); \
  y[7] = kTetraprobeY2n2 * d.x * d.z;              \
  y[8] = kTetraprobeY22 * (d.x * d.x - d.y * d.y)

float[9] tetraprobeShBasis(vec3 d) {
  precise float y[9];
  TETRAPROBE_SH_BASIS(y, d);
  return y;
}

// Cosine-lobe factor A_l of coefficient i.
float tetraprobeShCosineLobe(int i) {
  return i == 0 ? kTetraprobeA0 : (i < 4 ? kTetraprobeA1 : kTetraprobeA2);
}

// Irradiance E(n) in W/m^2 from 9 RGB radiance coefficients; n is a unit normal. Can be negative (ringing).
vec3 tetraprobeShIrradiance(vec3 c[9], vec3 n) {
  precise float y[9];
  TETRAPROBE_SH_BASIS(y, n);
  precise vec3 e = vec3(0.0);
  for (int i = 0; i < 9; ++i) e += c[i] * (y[i] * tetraprobeShCosineLobe(i));
  return e;
}

#endif  // TETRAPROBE_SH_GLSL
