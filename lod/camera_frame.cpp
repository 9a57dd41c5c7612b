#include <scan2lod/lod/camera_frame.h>

#include <scan2lod/core/error.h>

#include <cstdio>

namespace scan2lod {
namespace {

std::string triple(const Vec3f& v) {
  char text[96];
  std::snprintf(text, sizeof text, "%g,%g,%g", double(v.x()), double(v.y()), double(v.z()));
  return text;
}

}  // namespace

void require_camera_frame(const CameraView& c, const std::string& asker) {
  const Vec3f view = c.target - c.eye;
  if (!(view.norm() > 0))
    throw InputError("", asker + ": the eye " + triple(c.eye) + " is the target " + triple(c.target) +
                             "; the eye must stand away from what it looks at");
  if (!(c.up.norm() > 0)) throw InputError("", asker + ": up " + triple(c.up) + " has no direction");
  // Under 1e-4 the sideways axis is too short to normalise reliably.
  if (!(view.normalized().cross(c.up.normalized()).norm() > 1e-4f))
    throw InputError("", asker + ": up " + triple(c.up) + " is parallel to the view direction " + triple(view) +
                             " (from the eye " + triple(c.eye) + " to the target " + triple(c.target) +
                             "); give an up across it");
}

}  // namespace scan2lod
