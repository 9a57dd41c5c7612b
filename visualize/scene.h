// What every picture shares: the camera framing, the look of shaded and
// wireframe surfaces, and number formatting for captions.
#pragma once

#include "core/types.h"

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
