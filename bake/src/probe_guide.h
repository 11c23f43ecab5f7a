// Directional guiding of a probe's sphere paths: where a probe's light arrives through a small solid angle
// (a doorway, a window, a lit patch seen past a corner), most of its uniformly drawn directions find nothing
// and its estimate converges slowly (q3 dm4ish: thousands of probes stopped at the path cap). A pilot of
// kGuidePilotPaths one-bounce paths over the sphere records where the light comes from in an equal-area histogram; the
// probe's later batches draw half their directions from that histogram and half uniformly, weighted by the
// mixture's density (multi-sample balance heuristic; Veach 1997, ch. 9), so the estimate stays unbiased
// whatever the histogram holds, and the uniform half bounds the weight of any direction (at most 2x a uniform
// sample's). Two gates keep it where it helps: the pilot's light must be concentrated
// (kGuideMinConcentration) and, since the pilot follows one bounce, at least kGuideMinOneBounceShare of what
// the probe's own paths found so far (bake_probes.cpp): without the second, Veach Ajar's and Sponza's probes,
// whose light comes over more bounces, got noisier, the guided half thinning the stratified uniform half. Figures:
// docs/accuracy.md#probe-guiding. The idea is path guiding's (Vorba et al. 2014, "On-line learning of parametric mixture models for
// light transport simulation"; Mueller et al. 2017, "Practical path guiding"), reduced to the first direction
// from a probe and a fixed histogram. Internal to the bake module.
#pragma once

#include <array>
#include <vector>

#include <glm/vec3.hpp>

namespace tetraprobe::bake_detail {

// The histogram: kGuideZBins bands of equal height in z (so of equal area: Archimedes) by kGuidePhiBins
// sectors in azimuth; every bin covers 4 pi / kGuideBins sr.
inline constexpr int kGuideZBins = 8;
inline constexpr int kGuidePhiBins = 16;
inline constexpr int kGuideBins = kGuideZBins * kGuidePhiBins;
inline constexpr int kGuidePilotPaths = 256;  // pilot paths a probe (two a bin)
// A probe is guided only where its pilot's light is concentrated: kGuideBins x sum_b p_b^2 (1 when every bin
// holds as much, k when the light fills 1/k of the sphere evenly) at least this. Where light comes from
// everywhere the guided half only loses the uniform half's stratification.
inline constexpr double kGuideMinConcentration = 4.0;
// ... and only where the pilot's one-bounce light is at least this share of the probe's light so far.
inline constexpr double kGuideMinOneBounceShare = 0.5;

// The bin of a unit direction (any finite direction; the poles and the seam go to a valid bin).
int guideBin(const glm::vec3& dir);

class ProbeGuide {
 public:
  // No guide: every direction uniform.
  ProbeGuide() = default;
  // From pilot radiance luminances at unit directions (equal weights: the directions are a stratified
  // sphere set): each bin's sum, blurred with its 8 neighbours (weights 1/2 each against 1 for the bin, the
  // azimuth wrapping round), is its probability. Non-finite or negative luminances count as 0. All zero:
  // no guide (active() false).
  ProbeGuide(const std::vector<glm::vec3>& dirs, const std::vector<float>& luminance);

  bool active() const { return active_; }
  // A direction drawn from the histogram (u1 picks the bin, u2 and u3 place it uniformly in the bin's solid
  // angle), u in [0, 1). Needs active().
  glm::vec3 sample(double u1, double u2, double u3) const;
  // The histogram's solid-angle density at a unit direction (1 / (4 pi) everywhere when not active).
  float pdf(const glm::vec3& dir) const;

 private:
  bool active_ = false;
  std::array<double, kGuideBins> cdf_{};     // cumulative probabilities, cdf_[kGuideBins - 1] == 1
  std::array<float, kGuideBins> density_{};  // probability / bin solid angle
};

}  // namespace tetraprobe::bake_detail
