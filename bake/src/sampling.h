// Direction and point sampling shared by the bake's algorithms: cosine-weighted and uniform hemispheres
// (Malley's method; Shirley & Chiu 1997 concentric map), uniform sphere, spherical Fibonacci point sets
// (Marques et al. 2013, "Spherical Fibonacci Point Sets for Illumination Integrals"), uniform random
// rotations (Shoemake 1992, "Uniform random rotations", Graphics Gems III), uniform triangle points (Osada et
// al. 2002), orthonormal bases (Duff et al. 2017, "Building an Orthonormal Basis, Revisited"), and the power
// heuristic for multiple importance sampling (Veach 1997). Internal to the bake module.
#pragma once

#include <cmath>
#include <numbers>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "rng.h"
#include "tetraprobe/runtime/luminance.h"

namespace tetraprobe::bake_detail {

inline constexpr float kPi = std::numbers::pi_v<float>;
inline constexpr float kInvPi = std::numbers::inv_pi_v<float>;

using ::tetraprobe::luminance;  // Rec. 709, runtime/luminance.h
inline float maxComponent(const glm::vec3& c) {
  return std::fmax(c.x, std::fmax(c.y, c.z));
}

// The solid-angle density, seen from a point `dist` away, of a point drawn on a surface with area density
// pdfArea, whose normal makes cosine cosAtPoint with the line between them: pdfArea dist^2 / cosAtPoint.
inline float solidAnglePdf(float pdfArea, float dist, float cosAtPoint) {
  return pdfArea * dist * dist / cosAtPoint;
}

// Power heuristic with beta = 2 for one sample from each of two strategies.
inline float powerHeuristic(float pdfA, float pdfB) {
  const float a = pdfA * pdfA, b = pdfB * pdfB;
  return a + b > 0.0f ? a / (a + b) : 0.0f;
}

// Tangent t and bitangent b with (t, b, n) right-handed orthonormal; n unit.
inline void orthonormalBasis(const glm::vec3& n, glm::vec3& t, glm::vec3& b) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float c = n.x * n.y * a;
  t = glm::vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
  b = glm::vec3(c, sign + n.y * n.y * a, -n.y);
}

// Concentric map of the unit square to the unit disc.
inline glm::vec2 concentricDisc(float u1, float u2) {
  const float x = 2.0f * u1 - 1.0f, y = 2.0f * u2 - 1.0f;
  if (x == 0.0f && y == 0.0f) return glm::vec2(0.0f);
  float r, phi;
  if (std::fabs(x) > std::fabs(y)) {
    r = x;
    phi = (kPi / 4.0f) * (y / x);
  } else {
    r = y;
    phi = (kPi / 2.0f) - (kPi / 4.0f) * (x / y);
  }
  return glm::vec2(r * std::cos(phi), r * std::sin(phi));
}

// Cosine-weighted direction about unit n; pdf = cos(theta) / pi.
inline glm::vec3 cosineHemisphere(const glm::vec3& n, float u1, float u2) {
  const glm::vec2 d = concentricDisc(u1, u2);
  const float z = std::sqrt(std::fmax(0.0f, 1.0f - d.x * d.x - d.y * d.y));
  glm::vec3 t, b;
  orthonormalBasis(n, t, b);
  return glm::normalize(t * d.x + b * d.y + n * z);
}

// Uniform direction on the unit sphere; pdf = 1 / (4 pi).
inline glm::vec3 uniformSphere(float u1, float u2) {
  const float z = 1.0f - 2.0f * u1;
  const float r = std::sqrt(std::fmax(0.0f, 1.0f - z * z));
  const float phi = 2.0f * kPi * u2;
  return glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
}

// Uniform direction on the hemisphere about unit n; pdf = 1 / (2 pi).
inline glm::vec3 uniformHemisphere(const glm::vec3& n, float u1, float u2) {
  const float z = u1;
  const float r = std::sqrt(std::fmax(0.0f, 1.0f - z * z));
  const float phi = 2.0f * kPi * u2;
  glm::vec3 t, b;
  orthonormalBasis(n, t, b);
  return glm::normalize(t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * z);
}

// Uniform direction inside the cone of half-angle acos(cosMax) about unit axis; pdf = 1 / (2 pi (1 -
// cosMax)).
inline glm::vec3 uniformCone(const glm::vec3& axis, float cosMax, float u1, float u2) {
  const float z = 1.0f - u1 * (1.0f - cosMax);
  const float r = std::sqrt(std::fmax(0.0f, 1.0f - z * z));
  const float phi = 2.0f * kPi * u2;
  glm::vec3 t, b;
  orthonormalBasis(axis, t, b);
  return glm::normalize(t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + axis * z);
}

// Point k of an n-point spherical Fibonacci set (equal-area latitude bands, golden-angle longitudes), in
// double.
inline glm::dvec3 sphericalFibonacci(int k, int n) {
  constexpr double kGoldenAngle = 2.399963229728653;  // pi (3 - sqrt 5)
  static_assert(kGoldenAngle > 2.3999632297286 && kGoldenAngle < 2.3999632297287, "pi (3 - sqrt 5)");
  const double z = 1.0 - (2.0 * k + 1.0) / n;
  const double r = std::sqrt(std::fmax(0.0, 1.0 - z * z));
  const double phi = kGoldenAngle * k;
  return glm::dvec3(r * std::cos(phi), r * std::sin(phi), z);
}

// Uniformly distributed random rotation from three uniforms (Shoemake's quaternion method).
inline glm::dmat3 randomRotation(double u1, double u2, double u3) {
  const double s1 = std::sqrt(1.0 - u1), s2 = std::sqrt(u1);
  const double a = 2.0 * std::numbers::pi * u2, b = 2.0 * std::numbers::pi * u3;
  const double x = s1 * std::sin(a), y = s1 * std::cos(a), z = s2 * std::sin(b), w = s2 * std::cos(b);
  // Column-major rotation matrix of the unit quaternion (x, y, z, w).
  return glm::dmat3(glm::dvec3(1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)),
                    glm::dvec3(2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)),
                    glm::dvec3(2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)));
}

// Barycentrics (u, v) of a uniform point on a triangle: point = (1-u-v) P0 + u P1 + v P2.
inline glm::vec2 uniformTriangle(float u1, float u2) {
  const float s = std::sqrt(u1);
  return glm::vec2(s * (1.0f - u2), s * u2);
}

}  // namespace tetraprobe::bake_detail
