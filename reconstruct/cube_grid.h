// The cubic grid that marching cubes runs on: R cubes per side over the bounding
// cube of the data (Lee 2007, §4.4), addressed sparsely by packed integer keys.
#pragma once

#include <scan2lod/core/types.h>

#include <cstdint>

namespace scan2lod {

// Grid coordinates are packed 20 bits per axis, so R may be up to 2^19. Eight
// of the R cubes are padding (make_cube_grid), so R = 16 is the coarsest grid
// with room for the data.
constexpr int kMinResolution = 16;
constexpr int kMaxResolution = 1 << 19;

struct CubeGrid {
  Vec3d origin = Vec3d::Zero();  // position of grid corner (0,0,0)
  double cube_size = 0.0;
  int resolution = 0;            // cubes per side

  Vec3f corner_position(std::int64_t x, std::int64_t y, std::int64_t z) const {
    return (origin + cube_size * Vec3d(double(x), double(y), double(z))).cast<float>();
  }
};

inline std::uint64_t pack_key(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
  return x | (y << 20) | (z << 40);
}
inline void unpack_key(std::uint64_t key, int* x, int* y, int* z) {
  *x = int(key & 0xfffff);
  *y = int((key >> 20) & 0xfffff);
  *z = int((key >> 40) & 0xfffff);
}

// The grid of `resolution` cubes per side whose cube is the box's bounding cube,
// centred, with four cubes of padding on every side so that the surface never
// touches the grid's border. Throws InputError for an empty/degenerate box or a
// resolution that is not a power of two in [kMinResolution, kMaxResolution].
CubeGrid make_cube_grid(const Aabb& box, int resolution);

}  // namespace scan2lod
