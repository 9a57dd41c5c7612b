#include <scan2lod/visualize/scene.h>

#include <vtkCamera.h>
#include <vtkProperty.h>

#include <scan2lod/core/error.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

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

void place_camera(vtkCamera* camera, const ViewCamera& view, const Aabb& box) {
  camera->SetViewAngle(view.fov_degrees);  // vertical, as UseHorizontalViewAngle is off
  camera->SetPosition(view.eye.x(), view.eye.y(), view.eye.z());
  camera->SetFocalPoint(view.target.x(), view.target.y(), view.target.z());
  camera->SetViewUp(view.up.x(), view.up.y(), view.up.z());
  camera->OrthogonalizeViewUp();
  const Vec3d centre = box.empty() ? view.target : Vec3d((0.5f * (box.min + box.max)).cast<double>());
  const double radius = std::max(1e-6, box.empty() ? 1.0 : 0.5 * double(box.diagonal()));
  const double distance = (view.eye - centre).norm();
  camera->SetClippingRange(std::max(distance - 1.5 * radius, 1e-3 * radius), distance + 1.5 * radius);
}

ViewCamera parse_view_camera(const std::string& text, const std::string& flag) {
  const std::string expected = flag + " expects EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV (eye, target, up, vertical field of "
                                      "view in degrees), got '" + text + "'";
  std::vector<double> v;
  std::size_t at = 0;
  for (bool last = false; !last; at += 1) {
    std::size_t end = text.find(',', at);
    last = end == std::string::npos;
    if (last) end = text.size();
    const std::string field = text.substr(at, end - at);
    char* stop = nullptr;
    const double value = std::strtod(field.c_str(), &stop);
    if (field.empty() || *stop != '\0' || !std::isfinite(value)) throw InputError("", expected);
    v.push_back(value);
    at = end;
  }
  if (v.size() != 10) throw InputError("", expected);
  ViewCamera view{Vec3d(v[0], v[1], v[2]), Vec3d(v[3], v[4], v[5]), Vec3d(v[6], v[7], v[8]), v[9]};
  const Vec3d forward = view.target - view.eye;
  if (forward.norm() == 0) throw InputError("", flag + ": the eye is at the target; " + expected);
  if (forward.normalized().cross(view.up).norm() < 1e-6)
    throw InputError("", flag + ": up must not lie along the view; " + expected);
  if (!(view.fov_degrees > 0 && view.fov_degrees < 180))
    throw InputError("", flag + ": the field of view must be between 0 and 180 degrees; " + expected);
  return view;
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
