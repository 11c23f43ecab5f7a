// `tetraprobe diff A.png B.png`: visual regression check for CI. Exit 0 when the images match within the
// thresholds, 1 when they differ, 2 for bad input (unreadable file, different sizes).
#include <cstdio>

#include "args.h"
#include "commands.h"
#include "image_compare.h"

namespace tetraprobe::cli {

int cmdDiff(int argc, char** argv) {
  Args args(
      "tetraprobe diff A.png B.png [--out DIFF.png] [--tolerance T] [--max-fraction F] [--json]",
      "Compares two images pixel by pixel. They match when at most F of the pixels differ by more than\n"
      "T (0..255) in some channel. Writes a diff image (differences x8 over a dimmed A) with --out.",
      {{"--out", "", "DIFF.png", "write the diff image", ""},
       {"--tolerance", "", "T", "per-channel difference a pixel may have and still match", "2"},
       {"--max-fraction", "", "F", "fraction of pixels allowed over the tolerance", "0.001"},
       {"--json", "", "", "print the figures as JSON", ""}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(2, 2);
  const int tolerance = args.integer("--tolerance");
  const double maxFraction = args.number("--max-fraction");
  if (tolerance < 0 || tolerance > 255) throw UsageError("--tolerance must be in [0, 255]");
  if (maxFraction < 0.0 || maxFraction > 1.0) throw UsageError("--max-fraction must be in [0, 1]");
  const Rgb8Image a = readImage8(args.positional()[0]);
  const Rgb8Image b = readImage8(args.positional()[1]);
  const ImageDiff d = compareImages(a, b, tolerance);
  const bool match = d.fractionOver <= maxFraction;
  if (args.has("--out")) writeImage8(args.str("--out"), d.visual);
  if (args.has("--json")) {
    const nlohmann::json j = {{"match", match},         {"mean_abs", d.meanAbs},
                              {"max_abs", d.maxAbs},    {"fraction_over", d.fractionOver},
                              {"tolerance", tolerance}, {"max_fraction", maxFraction}};
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("%s: mean |diff| %.3f, max %d, %.4f%% of pixels over %d\n", match ? "match" : "DIFFER",
                d.meanAbs, d.maxAbs, 100.0 * d.fractionOver, tolerance);
  }
  return match ? 0 : 1;
}

}  // namespace tetraprobe::cli
