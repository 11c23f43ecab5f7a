// Build-side error types. Libraries throw these; the CLI maps them to exit codes (InputError -> 2, any other
// std::exception -> 1) and prints the message as one line on stderr. The runtime never throws.
#pragma once

#include <stdexcept>
#include <string>

namespace tetraprobe {

// Bad data from outside: a file, a scene, a CLI argument. The message names the input and the problem,
// e.g. "scene.obj: line 12: vertex index 99 out of range (41 vertices)".
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace tetraprobe
