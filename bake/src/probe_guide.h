// Directional guiding of a probe's sphere paths: where a probe's light arrives through a small solid angle
// (a doorway, a window, a lit patch seen past a corner), most of its uniformly drawn directions find little
// and its estimate converges slowly (q3 dm4ish: thousands of probes stopped at the path cap). The probe's own
// paths record where its light comes from in an equal-area histogram (each path's luminance, weighted by the
// inverse of the density its direction was drawn with, in the bin of its first direction); once
// kGuideLearnBatches batches are in, half of each later batch's directions are drawn from the histogram and
// half uniformly, every direction weighted by the mixture's density (multi-sample balance heuristic; Veach
// 1997, ch. 9). The estimate stays unbiased whatever the histogram holds (a batch's guide depends only on
// earlier batches), and the uniform half bounds any direction's weight at 2x a uniform sample's. The idea is
// path guiding's (Vorba et al. 2014, "On-line learning of parametric mixture models for light transport
// simulation"; Mueller et al. 2017, "Practical path guiding"), reduced to the first direction from a probe
// and a histogram rebuilt every kGuideLearnBatches batches. Figures: docs/accuracy.md#probe-guiding.
// Internal to the bake module.
#pragma once

#include <array>

#include <glm/vec3.hpp>

namespace tetraprobe::bake_detail {

// The histogram: kGuideZBins bands of equal height in z (so of equal area: Archimedes) by kGuidePhiBins
// sectors in azimuth; every bin covers 4 pi / kGuideBins sr.
inline constexpr int kGuideZBins = 8;
inline constexpr int kGuidePhiBins = 16;
inline constexpr int kGuideBins = kGuideZBins * kGuidePhiBins;
// Uniform batches recorded before the first guided one, and how often the guide is rebuilt (batches).
inline constexpr int kGuideLearnBatches = 4;

// The bin of a unit direction (any finite direction; the poles and the seam go to a valid bin).
int guideBin(const glm::vec3& dir);

// Light per bin, summed over samples (non-finite or negative values count as 0).
struct GuideHistogram {
  std::array<double, kGuideBins> sum{};
  void add(const glm::vec3& dir, double value);
};

class ProbeGuide {
 public:
  // No guide: every direction uniform.
  ProbeGuide() = default;
  // Each bin's sum, blurred with its 8 neighbours (weight 1/8 each against 1 for the bin, the azimuth
  // wrapping round), is its probability. All zero: no guide (active() false).
  explicit ProbeGuide(const GuideHistogram& histogram);

  bool active() const { return active_; }
  // A direction drawn from the histogram (u1 picks the bin by the cumulative distribution, u2 and u3 place it
  // uniformly in the bin's solid angle), u in [0, 1). Needs active().
  glm::vec3 sample(double u1, double u2, double u3) const;
  // The histogram's solid-angle density at a unit direction (1 / (4 pi) everywhere when not active).
  float pdf(const glm::vec3& dir) const;

 private:
  bool active_ = false;
  std::array<double, kGuideBins> cdf_{};     // cumulative probabilities, cdf_[kGuideBins - 1] == 1
  std::array<float, kGuideBins> density_{};  // probability / bin solid angle
};

}  // namespace tetraprobe::bake_detail
