// What a caller asks one level by, checked before any model is read: exactly
// one of a percent, a triangle budget, an object-space error, a camera or an
// octree priority, each within its range. `scan2lod extract` and the Python
// package's Model.extract() both go through it, so that a bad request is
// refused by one rule with one message, the option named as that caller
// spells it ("--pixel-error" or "pixel_error").
#pragma once

#include <scan2lod/lod/lod_model.h>

#include <cstdint>
#include <optional>
#include <string>

namespace scan2lod {

struct LevelChoice {
  std::optional<double> percent;          // 0 to 100
  std::optional<std::int64_t> triangles;  // >= 0
  bool at_most = false;                   // with triangles: never more than it
  bool stored_cut = false;                // with percent or triangles: a stored cut, not refined to the count
  std::optional<double> error;            // finite, >= 0
  std::optional<CameraView> camera;       // eye, target and up; fov_degrees and height too
  double pixel_error = 1;                 // > 0; with a camera
  std::optional<std::int64_t> priority;   // >= 0
};

// How option names are written in messages.
enum class OptionSpelling {
  kCommandLine,  // "--pixel-error"
  kKeywords,     // "pixel_error"
};

// `name` (with underscores, "pixel_error") as `spelling` writes it.
std::string option_name(const std::string& name, OptionSpelling spelling);

// The request `choice` makes. Throws InputError naming the option when not
// exactly one kind is given, when a value is out of its range (percent
// outside [0, 100], a negative budget or priority, an error that is negative
// or not finite, stored_cut without a percent or triangles, a field of view
// outside (0, 180) degrees, a height under 1, a pixel error not above 0), or
// when the camera has no frame to project with (lod/camera_frame.h).
LevelRequest level_request(const LevelChoice& choice, OptionSpelling spelling);

}  // namespace scan2lod
