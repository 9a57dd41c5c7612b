#include <scan2lod/lod/level_choice.h>

#include <scan2lod/core/error.h>
#include <scan2lod/lod/camera_frame.h>

#include <cmath>
#include <cstdio>

namespace scan2lod {
namespace {

std::string number(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

int kinds_given(const LevelChoice& c) {
  return int(c.percent.has_value()) + int(c.triangles.has_value()) + int(c.error.has_value()) +
         int(c.camera.has_value()) + int(c.priority.has_value());
}

void check_ranges(const LevelChoice& c, OptionSpelling spelling) {
  const auto name = [spelling](const char* n) { return option_name(n, spelling); };
  if (c.percent && !(*c.percent >= 0 && *c.percent <= 100))
    throw InputError("", name("percent") + " must be between 0 and 100, got " + number(*c.percent));
  if (c.triangles && *c.triangles < 0)
    throw InputError("", name("triangles") + " must not be negative, got " + std::to_string(*c.triangles));
  if (c.priority && *c.priority < 0)
    throw InputError("", name("priority") + " must not be negative, got " + std::to_string(*c.priority));
  if (c.error && !(*c.error >= 0 && std::isfinite(*c.error)))
    throw InputError("", name("error") + " must be a finite number >= 0, got " + number(*c.error));
  if (!(c.pixel_error > 0))
    throw InputError("", name("pixel_error") + " must be > 0, got " + number(c.pixel_error));
  // Given with an error, camera or priority it would change nothing.
  if (c.stored_cut && !c.percent && !c.triangles)
    throw InputError("", name("stored_cut") + " applies to " + name("percent") + " and " + name("triangles") +
                             " only: other requests are not refined");
  if (!c.camera) return;
  if (!(c.camera->fov_degrees > 0 && c.camera->fov_degrees < 180))
    throw InputError("", name("fov") + " must be in (0, 180) degrees, got " + number(c.camera->fov_degrees));
  if (c.camera->height < 1)
    throw InputError("", name("height") + " must be >= 1, got " + std::to_string(c.camera->height));
  require_camera_frame(*c.camera, name("camera"));
}

}  // namespace

std::string option_name(const std::string& name, OptionSpelling spelling) {
  if (spelling == OptionSpelling::kKeywords) return name;
  std::string flag = "--" + name;
  for (char& ch : flag)
    if (ch == '_') ch = '-';
  return flag;
}

LevelRequest level_request(const LevelChoice& c, OptionSpelling spelling) {
  if (const int given = kinds_given(c); given != 1) {
    const auto name = [spelling](const char* n) { return option_name(n, spelling); };
    throw InputError("", "extract needs exactly one of " + name("percent") + ", " + name("triangles") + ", " +
                             name("error") + ", " + name("camera") + " and " + name("priority") + ", got " +
                             std::to_string(given));
  }
  check_ranges(c, spelling);
  if (c.percent || c.triangles) {
    LevelRequest r = c.percent      ? LevelRequest::at_percent(*c.percent)
                     : c.at_most    ? LevelRequest::at_most_triangles(*c.triangles)
                                    : LevelRequest::at_triangles(*c.triangles);
    r.refine = !c.stored_cut;
    return r;
  }
  if (c.error) return LevelRequest::at_error(*c.error);
  if (c.priority) return LevelRequest::at_priority(std::size_t(*c.priority));
  return LevelRequest::for_camera(*c.camera, c.pixel_error);
}

}  // namespace scan2lod
