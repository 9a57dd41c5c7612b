#include "visualize/scene.h"

#include <vtkCamera.h>
#include <vtkProperty.h>

#include <algorithm>
#include <cmath>

namespace scan2lod {

void frame_camera(vtkCamera* camera, const Aabb& box, double azimuth, double elevation, double aspect) {
  const Vec3d centre = box.empty() ? Vec3d(Vec3d::Zero()) : Vec3d((0.5f * (box.min + box.max)).cast<double>());
  const double radius = std::max(1e-6, box.empty() ? 1.0 : 0.5 * double(box.diagonal()));
  const double angle = 30.0;
  // The sphere's silhouette fills the narrower side; the box rarely fills its
  // sphere, so a little closer than the sphere's tangent distance.
  double distance = 0.8 * radius / std::sin(0.5 * angle * M_PI / 180.0);
  if (aspect > 0 && aspect < 1) distance /= aspect;
  camera->SetViewAngle(angle);
  camera->SetFocalPoint(centre.x(), centre.y(), centre.z());
  camera->SetPosition(centre.x(), centre.y(), centre.z() + distance);
  camera->SetViewUp(0, 1, 0);
  camera->Azimuth(azimuth);
  camera->Elevation(elevation);
  camera->OrthogonalizeViewUp();
  camera->SetClippingRange(std::max(distance - 1.5 * radius, 0.01 * radius), distance + 1.5 * radius);
}

void style_shaded(vtkProperty* p) {
  p->SetRepresentationToSurface();
  p->SetInterpolationToGouraud();
  p->SetColor(0.87, 0.82, 0.70);
  p->SetAmbient(0.12);
  p->SetDiffuse(0.85);
  p->SetSpecular(0.15);
  p->SetSpecularPower(20);
  p->EdgeVisibilityOff();
  p->LightingOn();
}

void style_wireframe(vtkProperty* p, double edge_pixels) {
  p->SetRepresentationToWireframe();
  p->SetLineWidth(1);
  if (edge_pixels >= 2) {  // every edge visible: black ink
    p->SetColor(0.08, 0.08, 0.08);
    p->LightingOff();
    return;
  }
  // Edges crowd the pixels: unlit they would merge into a flat blot, so the
  // lines are lit like a surface and lighter the denser they are.
  const double grey = 0.75 - 0.35 * std::clamp(edge_pixels - 1.0, 0.0, 1.0);
  p->SetColor(grey, grey, grey);
  p->LightingOn();
  p->SetAmbient(0.15);
  p->SetDiffuse(0.85);
  p->SetSpecular(0);
}

std::string thousands(std::size_t n) {
  std::string digits = std::to_string(n), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ' ';
    out += digits[i];
  }
  return out;
}

}  // namespace scan2lod
