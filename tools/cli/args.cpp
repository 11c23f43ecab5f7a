// Command-line option parsing with generated --help.
#include "args.h"

#include "tetraprobe/bake/bake.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace tetraprobe::cli {

Args::Args(std::string usage, std::string summary, std::vector<OptionSpec> options)
    : usage_(std::move(usage)), summary_(std::move(summary)), options_(std::move(options)) {
  options_.push_back({"--help", "-h", "", "show this help and exit", ""});
}

const OptionSpec& Args::spec(const std::string& name) const {
  for (const auto& o : options_)
    if (o.name == name || (!o.alias.empty() && o.alias == name)) return o;
  throw UsageError("unknown option '" + name + "' (see --help)");
}

bool Args::parse(int argc, char** argv) {
  for (int i = 0; i < argc; ++i) {
    std::string a = argv[i];
    if (a.size() > 1 && a[0] == '-' && !(a.size() > 1 && (std::isdigit(a[1]) || a[1] == '.'))) {
      std::string value;
      bool inlineValue = false;
      if (const auto eq = a.find('='); a.rfind("--", 0) == 0 && eq != std::string::npos) {
        value = a.substr(eq + 1);
        a = a.substr(0, eq);
        inlineValue = true;
      }
      const OptionSpec& o = spec(a);
      if (o.name == "--help") {
        printHelp();
        return false;
      }
      if (o.valueName.empty()) {
        if (inlineValue) throw UsageError("option " + o.name + " takes no value");
        values_[o.name] = "1";
      } else {
        if (!inlineValue) {
          if (i + 1 >= argc) throw UsageError("option " + o.name + " needs a value " + o.valueName);
          value = argv[++i];
        }
        values_[o.name] = value;
      }
    } else {
      positional_.push_back(a);
    }
  }
  return true;
}

void Args::requirePositional(size_t min, size_t max) const {
  if (positional_.size() < min) throw UsageError("missing arguments; usage: " + usage_);
  if (positional_.size() > max)
    throw UsageError("unexpected argument '" + positional_[max] + "'; usage: " + usage_);
}

bool Args::has(const std::string& name) const {
  return values_.count(spec(name).name) > 0;
}

std::string Args::str(const std::string& name) const {
  const OptionSpec& o = spec(name);
  auto it = values_.find(o.name);
  return it != values_.end() ? it->second : o.defaultValue;
}

double parseNumber(const std::string& text, const std::string& what) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v))
    throw UsageError(what + ": '" + text + "' is not a finite number");
  return v;
}

IndexOfCount parseIndexOfCount(const std::string& text, const std::string& flag) {
  const size_t slash = text.find('/');
  const double i = slash == std::string::npos ? -1 : parseNumber(text.substr(0, slash), flag + " I");
  const double n = slash == std::string::npos ? -1 : parseNumber(text.substr(slash + 1), flag + " N");
  if (!(n >= 1 && n <= 65536 && i >= 0 && i < n && i == std::floor(i) && n == std::floor(n)))
    throw UsageError(flag + " must be I/N with integers 0 <= I < N <= 65536, not '" + text + "'");
  return {int(i), int(n)};
}

uint64_t parseU64(const std::string& text, const std::string& what) {
  constexpr uint64_t kMax = std::numeric_limits<uint64_t>::max();
  uint64_t v = 0;
  bool ok = !text.empty();
  for (const char c : text) {
    const uint64_t digit = uint64_t(c - '0');
    if (c < '0' || c > '9' || v > (kMax - digit) / 10) {
      ok = false;
      break;
    }
    v = v * 10 + digit;
  }
  if (!ok) throw UsageError(what + ": '" + text + "' is not an integer in [0, " + std::to_string(kMax) + "]");
  return v;
}

double Args::number(const std::string& name) const {
  return parseNumber(str(name), name);
}

int Args::integer(const std::string& name) const {
  const double v = number(name);
  if (v != std::floor(v) || std::abs(v) > 2e9)
    throw UsageError(name + ": '" + str(name) + "' is not an integer");
  return int(v);
}

uint64_t Args::u64(const std::string& name) const {
  return parseU64(str(name), name);
}

int Args::bounces(const std::string& name) const {
  if (str(name) == "unbounded") return kUnboundedBounces;
  const int v = integer(name);
  if (v < 0 || v > 1000)
    throw UsageError(name + " must be 'unbounded' or in [0, 1000], not '" + str(name) + "'");
  return v;
}

glm::vec3 Args::vec3(const std::string& name) const {
  const std::string s = str(name);
  std::stringstream ss(s);
  std::string part;
  glm::vec3 v(0.0f);
  int k = 0;
  while (std::getline(ss, part, ',')) {
    if (k >= 3) throw UsageError(name + ": '" + s + "' must be X,Y,Z");
    v[k++] = float(parseNumber(part, name));
  }
  if (k != 3) throw UsageError(name + ": '" + s + "' must be X,Y,Z");
  return v;
}

void Args::printHelp() const {
  std::printf("usage: %s\n\n%s\n\noptions:\n", usage_.c_str(), summary_.c_str());
  for (const auto& o : options_) {
    std::string left = "  " + (o.alias.empty() ? std::string() : o.alias + ", ") + o.name;
    if (!o.valueName.empty()) left += " " + o.valueName;
    std::string help = o.help;
    if (!o.defaultValue.empty()) help += " (default: " + o.defaultValue + ")";
    std::printf("%-30s %s\n", left.c_str(), help.c_str());
  }
}

}  // namespace tetraprobe::cli
