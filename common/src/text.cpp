// Field trimming and strict finite-number parsing (std::from_chars, locale independent).
#include "tetraprobe/common/text.h"

#include <charconv>
#include <cmath>

namespace tetraprobe {

std::string_view trimWhitespace(std::string_view s) {
  const char* ws = " \t\r\n\v\f";
  const size_t b = s.find_first_not_of(ws);
  if (b == std::string_view::npos) return {};
  return s.substr(b, s.find_last_not_of(ws) - b + 1);
}

bool parseFiniteField(std::string_view field, double& out) {
  field = trimWhitespace(field);
  if (field.empty()) return false;
  if (field.front() == '+') field.remove_prefix(1);  // from_chars rejects a leading '+'
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), out);
  return ec == std::errc() && end == field.data() + field.size() && std::isfinite(out);
}

}  // namespace tetraprobe
