// The keyword options of reconstruct() and build(): the command line's
// reconstruction flags (cli/reconstruct_flags.h) by their names with
// underscores, onto the same option structs, so that a keyword and its flag
// mean one thing:
//   margin, distance ("planes", "hoppe" or "seed"), neighbours,
//   max_distance, reach, min_piece, max_hole, hole_rounds
// (defaults: ReconstructOptions, reconstruct/marching_cubes.h). An unknown
// keyword raises TypeError naming it, as Python does for a named parameter.
#pragma once

#include <scan2lod/reconstruct/marching_cubes.h>

#include <pybind11/pybind11.h>

#include <string>

namespace scan2lod::python {

// Keywords are taken out of `options` as they are used, so that a caller
// can take its own first and call unknown_keywords() last.
class KeywordOptions {
 public:
  KeywordOptions(const pybind11::kwargs& options, std::string function);

  // The reconstruction's options: `resolution` and `threads` (0: all cores;
  // negative raises ValueError) and the keywords above.
  ReconstructOptions reconstruct(int resolution, int threads);

  // Takes `key` if given, converted to T; TypeError names the keyword when
  // the value is not a T.
  template <typename T>
  bool take(const char* key, T* value);

  // Raises TypeError naming the first keyword nobody took.
  void refuse_unknown() const;

 private:
  pybind11::dict left_;
  std::string function_;
};

template <typename T>
bool KeywordOptions::take(const char* key, T* value) {
  if (!left_.contains(key)) return false;
  const pybind11::object given = left_[key];
  PyDict_DelItemString(left_.ptr(), key);
  try {
    *value = given.cast<T>();
  } catch (const pybind11::cast_error&) {
    throw pybind11::type_error(function_ + "(): " + key + " got " +
                               pybind11::str(pybind11::type::handle_of(given).attr("__name__")).cast<std::string>() +
                               " " + pybind11::repr(given).cast<std::string>());
  }
  return true;
}

}  // namespace scan2lod::python
