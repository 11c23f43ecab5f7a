// `tetraprobe diff A.png B.png`: visual regression check for CI. Exit 0 when the images match within the
// thresholds, 1 when they differ, 2 for bad input (unreadable file, different sizes).
#include <cstdio>
#include <string>
#include <utility>

#include "args.h"
#include "commands.h"
#include "image_compare.h"

namespace tetraprobe::cli {

int cmdDiff(int argc, char** argv) {
  const DiffThresholds defaults;
  Args args(
      "tetraprobe diff A.png B.png [--out DIFF.png] [--tolerance T] [--max-fraction F] [--max-window W]\n"
      "                [--max-changed C] [--json]",
      "Compares two images pixel by pixel. A pixel differs when some channel differs by more than T\n"
      "(0..255). They match when at most F of the pixels differ (scattered edges), at most W of the\n"
      "pixels of any 16x16 window differ (no blob), and at most C of the pixels change at all (no shift\n"
      "below T spread over the image); docs/evaluation.md#visual-regression. Writes a diff image\n"
      "(differences x8 over a dimmed A) with --out.",
      {{"--out", "", "DIFF.png", "write the diff image", ""},
       {"--tolerance", "", "T", "per-channel difference a pixel may have and still match",
        std::to_string(defaults.tolerance)},
       {"--max-fraction", "", "F", "fraction of pixels allowed over the tolerance", "0.001"},
       {"--max-window", "", "W", "fraction of any 16x16 window allowed over the tolerance", "0.125"},
       {"--max-changed", "", "C", "fraction of pixels allowed to change at all", "0.005"},
       {"--json", "", "", "print the figures as JSON", ""}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(2, 2);
  DiffThresholds t;
  t.tolerance = args.integer("--tolerance");
  t.maxFraction = args.number("--max-fraction");
  t.maxWindow = args.number("--max-window");
  t.maxChanged = args.number("--max-changed");
  if (t.tolerance < 0 || t.tolerance > 255) throw UsageError("--tolerance must be in [0, 255]");
  for (const auto& [name, v] :
       {std::pair{"--max-fraction", t.maxFraction}, std::pair{"--max-window", t.maxWindow},
        std::pair{"--max-changed", t.maxChanged}})
    if (!(v >= 0.0 && v <= 1.0)) throw UsageError(std::string(name) + " must be in [0, 1]");
  const Rgb8Image a = readImage8(args.positional()[0]);
  const Rgb8Image b = readImage8(args.positional()[1]);
  const ImageDiff d = compareImages(a, b, t.tolerance);
  const bool match = imagesMatch(d, t);
  if (args.has("--out")) writeImage8(args.str("--out"), d.visual);
  if (args.has("--json")) {
    const nlohmann::json j = {{"match", match},
                              {"mean_abs", d.meanAbs},
                              {"max_abs", d.maxAbs},
                              {"fraction_over", d.fractionOver},
                              {"worst_window_fraction", d.worstWindowFraction},
                              {"fraction_changed", d.fractionChanged},
                              {"tolerance", t.tolerance},
                              {"max_fraction", t.maxFraction},
                              {"max_window", t.maxWindow},
                              {"max_changed", t.maxChanged}};
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf(
        "%s: mean |diff| %.3f, max %d, %.4f%% of pixels over %d (limit %g%%), worst 16x16 window "
        "%.1f%% over (limit %g%%), %.4f%% changed (limit %g%%)\n",
        match ? "match" : "DIFFER", d.meanAbs, d.maxAbs, 100.0 * d.fractionOver, t.tolerance,
        100.0 * t.maxFraction, 100.0 * d.worstWindowFraction, 100.0 * t.maxWindow, 100.0 * d.fractionChanged,
        100.0 * t.maxChanged);
  }
  return match ? 0 : 1;
}

}  // namespace tetraprobe::cli
