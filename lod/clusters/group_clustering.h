// The coarse end of the cluster hierarchy: a group that edge collapse could
// not simplify, simplified by vertex clustering inside the group.
//
// Edge collapse under the link condition never changes topology, so a scan
// of high genus stalls once its groups are mostly handles: the hierarchy of a
// reconstruction with a hundred handles stopped at 1,235 triangles. Clustering
// the group's free vertices in a grid, each cell drawn to the vertex its
// quadric likes best (Rossignac and Borrel, *Multi-resolution 3D
// approximations for rendering complex scenes*, 1993; Lindstrom,
// *Out-of-core simplification of large polygonal models*, 2000), collapses
// thin tubes to nothing and caps where they were attached: handles close.
//
// The result stays a sound surface: no edge on three triangles, no vertex
// whose triangles are not one fan, no triangle turned over, no new boundary,
// no piece lost, and no new edge between two locked vertices (a neighbouring
// group might make it too). A cell whose clustering breaks one of these is
// split back into its vertices and the group clustered again, as Shaffer and
// Garland's adaptive cells (*Efficient adaptive simplification of massive
// meshes*, 2001) follow the surface rather than a fixed grid. Locked vertices
// and the scan's real boundary stay where they are.
#pragma once

#include <scan2lod/lod/clusters/group_simplify.h>

namespace scan2lod {

// What a clustering must keep. kManifold: all of the above. kPiecesOnly:
// no piece lost and no new edge between locked vertices, while edges may
// join more than two triangles: the hierarchy's last step, from where the
// rounds stall to a few hundred triangles, below the cuts that must stay
// sound.
enum class ClusterSoundness { kManifold, kPiecesOnly };

// Simplifies `triangles` (welded, as simplify_group takes them) towards
// `target` triangles by clustering, in cells that grow until the target is
// met or the group no longer shrinks. Returns the smallest result found that
// keeps `soundness` (the input itself when none is smaller), with its
// measured error.
SimplifiedGroup cluster_group(const std::vector<Triangle>& triangles, std::size_t target,
                              const SimplifyInput& input, ClusterSoundness soundness = ClusterSoundness::kManifold);

}  // namespace scan2lod
