// Vertices at one position share one id: split attributes (a seam of
// normals or colours) must not split adjacency, locks or collapses.
#pragma once

#include <scan2lod/core/array_view.h>
#include <scan2lod/core/types.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

// Per position, the smallest index holding the same point (by sorting on
// `threads` cores).
std::vector<std::int32_t> weld_positions(ArrayView<Vec3f> positions, int threads);

}  // namespace scan2lod
