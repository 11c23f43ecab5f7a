// Minimal command-line parsing for the tetraprobe subcommands: declared options with help text, positional
// arguments, and one-line usage errors (exit code 2).
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace tetraprobe::cli {

// Bad usage: unknown option, missing value, malformed number. The CLI prints it and exits with 2.
class UsageError : public std::runtime_error {
 public:
  explicit UsageError(const std::string& what) : std::runtime_error(what) {}
};

struct OptionSpec {
  std::string name;  // "--spacing" (and optional short alias in `alias`, e.g. "-o")
  std::string alias;
  std::string valueName;  // empty for a flag
  std::string help;
  std::string defaultValue;
};

// Whether `s` ends in `suffix` (exact bytes, case-sensitive).
inline bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

class Args {
 public:
  // `usage`: "tetraprobe bake SCENE -o LEVEL.tpb [options]"; `summary`: one paragraph.
  Args(std::string usage, std::string summary, std::vector<OptionSpec> options);

  // Parses argv (after the subcommand). Returns false when --help was asked (help already printed to stdout).
  bool parse(int argc, char** argv);

  const std::vector<std::string>& positional() const { return positional_; }
  // The options given, by canonical name (aliases resolved), in name order; flags hold "1".
  const std::map<std::string, std::string>& values() const { return values_; }
  void requirePositional(size_t min, size_t max) const;

  bool has(const std::string& name) const;
  std::string str(const std::string& name) const;  // value or default
  double number(const std::string& name) const;
  int integer(const std::string& name) const;
  // An unsigned 64-bit integer (parseU64): seeds.
  uint64_t u64(const std::string& name) const;
  // Path depth: "unbounded" (kUnboundedBounces: Russian roulette only) or an integer in [0, 1000].
  int bounces(const std::string& name) const;
  glm::vec3 vec3(const std::string& name) const;  // "x,y,z"
  void printHelp() const;

 private:
  const OptionSpec& spec(const std::string& name) const;
  std::string usage_, summary_;
  std::vector<OptionSpec> options_;
  std::map<std::string, std::string> values_;
  std::vector<std::string> positional_;
};

double parseNumber(const std::string& text, const std::string& what);

// One of N: `text` as "I/N" with integers 0 <= I < N <= 65536 (a shard, a farm worker); anything else is a
// UsageError naming `flag`.
struct IndexOfCount {
  int index = 0, count = 1;
};
IndexOfCount parseIndexOfCount(const std::string& text, const std::string& flag);

// `text` as an unsigned 64-bit integer: decimal digits only (no sign, point, exponent or spaces), at most
// 18446744073709551615; anything else is a UsageError naming `what`.
uint64_t parseU64(const std::string& text, const std::string& what);

}  // namespace tetraprobe::cli
