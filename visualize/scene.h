// What every picture shares: the camera framing, the look of shaded and
// wireframe surfaces, and number formatting for captions.
#pragma once

#include <scan2lod/core/types.h>

#include <cstddef>
#include <string>

class vtkCamera;
class vtkProperty;

namespace scan2lod {

// Points `camera` at the centre of `box` from the default direction (down -z,
// +y up) turned by `azimuth` and `elevation` degrees, at the distance where the
// box's bounding sphere fills a view of width/height `aspect`, with clipping
// planes around the sphere. The same box gives the same camera, so every level
// of a model is seen from one place.
void frame_camera(vtkCamera* camera, const Aabb& box, double azimuth, double elevation, double aspect);

// A camera given in full: a perspective view from `eye` towards `target`
// with `up` (made perpendicular to the view), and a vertical field of view,
// as three.js's PerspectiveCamera and CesiumJS's take it, so that a picture
// here and one in a browser can be compared pixel for pixel.
struct ViewCamera {
  Vec3d eye = Vec3d(0, 0, 1), target = Vec3d::Zero(), up = Vec3d(0, 1, 0);
  double fov_degrees = 30;
};

// Puts `camera` where `view` says, with clipping planes around `box` (which
// the view need not frame).
void place_camera(vtkCamera* camera, const ViewCamera& view, const Aabb& box);

// Parses "EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV" (eye, target, up, vertical field of
// view in degrees). Throws InputError naming `flag` unless it is ten finite
// numbers with eye != target, up not along the view, and 0 < FOV < 180.
ViewCamera parse_view_camera(const std::string& text, const std::string& flag);

// Light ivory, Gouraud-shaded with a little specular: the shaded panels.
void style_shaded(vtkProperty* property);
// Thin near-black unlit lines: the wireframe panels.
// Black lines while edges span 2 pixels or more (`edge_pixels`: a level's
// mean edge length on screen); denser, lit grey lines, so that a dense mesh
// reads as a shaded shape instead of a black blot.
void style_wireframe(vtkProperty* property, double edge_pixels = 8);

// 429247 -> "429 247" (thin groups read better in captions).
std::string thousands(std::size_t n);

}  // namespace scan2lod
