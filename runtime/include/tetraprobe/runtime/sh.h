// Real spherical harmonics up to L2 (9 coefficients), used by the baker, the CPU runtime and (mirrored in
// shaders/tetraprobe_sh.glsl) the GPU. Permissive: standard library and GLM only.
//
// Conventions (contract for every caller):
// - Real SH basis without the Condon-Shortley phase; coefficient index i = l*(l+1)+m, so
//   0:(0,0) 1:(1,-1)~y 2:(1,0)~z 3:(1,1)~x 4:(2,-2)~xy 5:(2,-1)~yz 6:(2,0)~(3z^2-1) 7:(2,1)~xz
//   8:(2,2)~(x^2-y^2).
// - Directions are unit vectors in the level's world frame (right-handed, metres; the frame of the input
//   file, usually +Y up). The basis does not care which axis is "up".
// - A probe stores *incident radiance* L(w) in W/(m^2 sr) per RGB channel, projected as
//   L_lm = integral L(w) Y_lm(w) dw. Irradiance on a surface with normal n is E(n) = sum A_l L_lm Y_lm(n) in
//   W/m^2, with A_0 = pi, A_1 = 2pi/3, A_2 = pi/4 (Ramamoorthi & Hanrahan 2001). Lambertian outgoing radiance
//   is albedo * E / pi.
// - An L1 probe is an L2 probe whose coefficients 4..8 are zero.
#pragma once

#include <array>
#include <cmath>
#include <numbers>

#include <glm/vec3.hpp>

namespace tetraprobe {

inline constexpr int kShCoeffCount = 9;

// Basis normalisation constants, each pinned beside its closed form.
namespace sh_const {
inline constexpr double kY00 = 0.28209479177387814;          // 1 / (2 sqrt(pi))
inline constexpr double kY1 = 0.4886025119029199;            // sqrt(3 / (4 pi))
inline constexpr double kY2n2 = 1.0925484305920792;          // sqrt(15 / pi) / 2     (xy, yz, xz)
inline constexpr double kY20 = 0.31539156525252005;          // sqrt(5 / pi) / 4      (3z^2 - 1)
inline constexpr double kY22 = 0.5462742152960396;           // sqrt(15 / pi) / 4     (x^2 - y^2)
inline constexpr double kA0 = std::numbers::pi;              // cosine-lobe convolution, band 0
inline constexpr double kA1 = 2.0 * std::numbers::pi / 3.0;  // band 1
inline constexpr double kA2 = std::numbers::pi / 4.0;        // band 2

constexpr double sqr(double x) {
  return x * x;
}
// The closed forms, checked at compile time (relative tolerance 1e-14: the literals carry 16-17 digits).
constexpr bool near(double a, double b) {
  return (a - b) < 1e-14 * b && (b - a) < 1e-14 * b;
}
static_assert(near(sqr(kY00) * 4.0 * std::numbers::pi, 1.0), "Y00 = 1/(2 sqrt(pi))");
static_assert(near(sqr(kY1) * 4.0 * std::numbers::pi, 3.0), "Y1 = sqrt(3/(4pi))");
static_assert(near(sqr(kY2n2) * 4.0 * std::numbers::pi, 15.0), "Y2,-2 = sqrt(15/pi)/2");
static_assert(near(sqr(kY20) * 16.0 * std::numbers::pi, 5.0), "Y20 = sqrt(5/pi)/4");
static_assert(near(sqr(kY22) * 16.0 * std::numbers::pi, 15.0), "Y22 = sqrt(15/pi)/4");
}  // namespace sh_const

// Incident radiance of one probe: 9 RGB coefficients (W/(m^2 sr)), index l*(l+1)+m. 108 bytes.
struct ShRgb {
  std::array<glm::vec3, kShCoeffCount> c{};
};
static_assert(sizeof(ShRgb) == 108, "ShRgb is 27 packed floats, shared with the GPU layout");

// Evaluates the 9 basis functions at unit direction d.
template <typename T>
constexpr std::array<T, kShCoeffCount> shBasis(T x, T y, T z) {
  using namespace sh_const;
  return {T(kY00),
          T(kY1) * y,
          T(kY1) * z,
          T(kY1) * x,
          T(kY2n2) * x * y,
          T(kY2n2) * y * z,
          T(kY20) * (T(3) * z * z - T(1)),
          T(kY2n2) * x * z,
          T(kY22) * (x * x - y * y)};
}

// Per-coefficient cosine-convolution factor A_l (band of coefficient i).
constexpr double shCosineLobe(int i) {
  return i == 0 ? sh_const::kA0 : (i < 4 ? sh_const::kA1 : sh_const::kA2);
}

// Irradiance E(n) in W/m^2 on a surface with unit normal n. Can be negative where the L2 projection rings.
glm::vec3 shIrradiance(const ShRgb& sh, const glm::vec3& n);

// Reconstructed incident radiance L(d) in W/(m^2 sr) from direction d (unit).
glm::vec3 shRadiance(const ShRgb& sh, const glm::vec3& d);

// Weighted sum sum_i w[i] * sh[i] of `count` probes (barycentric interpolation).
ShRgb shBlend(const ShRgb* const* probes, const float* weights, int count);

}  // namespace tetraprobe
