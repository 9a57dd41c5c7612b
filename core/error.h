// Errors a user can act on: which file, which element, what was expected.
#pragma once

#include <stdexcept>
#include <string>

namespace scan2lod {

class InputError : public std::runtime_error {
 public:
  // "FILE: WHAT" — what names the element and what was expected instead.
  InputError(const std::string& file, const std::string& what)
      : std::runtime_error(file.empty() ? what : file + ": " + what) {}
};

}  // namespace scan2lod
