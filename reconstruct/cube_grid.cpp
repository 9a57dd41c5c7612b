#include <scan2lod/reconstruct/cube_grid.h>

#include <scan2lod/core/error.h>

namespace scan2lod {

CubeGrid make_cube_grid(const Aabb& box, int resolution) {
  if (resolution < kMinResolution || resolution > kMaxResolution || (resolution & (resolution - 1)) != 0)
    throw InputError("", "resolution must be a power of two from " + std::to_string(kMinResolution) + " to " +
                             std::to_string(kMaxResolution) + ", got " + std::to_string(resolution));
  if (box.empty() || !box.min.allFinite() || !box.max.allFinite())
    throw InputError("", "the input points have no finite bounding box");
  const double extent = box.extent().cast<double>().maxCoeff();
  if (!(extent > 0.0))
    throw InputError("", "the input points span a zero-size box: no grid can be laid over them");
  CubeGrid grid;
  grid.resolution = resolution;
  grid.cube_size = extent / double(resolution - 8);
  const Vec3d centre = 0.5 * (box.min.cast<double>() + box.max.cast<double>());
  grid.origin = centre - Vec3d::Constant(0.5 * resolution * grid.cube_size);
  return grid;
}

}  // namespace scan2lod
