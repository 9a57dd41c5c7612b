// Crack patching between octree levels (Lee 2007, §5.3, done as conforming
// transitions rather than Lee's projection, which leaves T-junctions).
//
// A node beside finer nodes is triangulated on its boundary refined to theirs:
// every node edge with a finer node around it is split at its midpoint, and
// every face with a finer node across it is split into four. Each face
// polygon joins its crossings by the same rule as the case table (each run of
// inside corners is cut off by one segment), which depends on the polygon's
// signs alone; both nodes on a face build the same polygon, so they join the
// same crossings and the mesh stays closed and conforming. The longest loop
// that the segments form is fanned around the node's centre vertex, any other
// from one of its own crossings (two sheets never share the centre).
//
// Local lattice: the node's 3x3x3 points (i, j, k) in {0,1,2}^3, index
// i + 3j + 9k; 1 is a midpoint. The 48 boundary sub-edges join neighbouring
// boundary points: 24 halves of node edges and 24 half-lines inside faces.
#pragma once

#include <scan2lod/core/types.h>

#include <array>
#include <cstdint>
#include <vector>

namespace scan2lod {

constexpr int kSubEdges = 48;

struct SubEdge {
  std::uint8_t a, b;  // local lattice points, a < b
};

// The 48 boundary sub-edges, in a fixed order.
const std::array<SubEdge, kSubEdges>& transition_sub_edges();

// Local lattice point of node corner c (corner numbering of cube_table.h).
int lattice_of_corner(int c);

// The 18 cells around a node (index (dx+1) + 3 (dy+1) + 9 (dz+1), as in
// McOctree::neighbours) across one of its faces or edges. Only a finer node
// in one of these changes the node's triangulation: one across a corner
// alone splits nothing.
const std::array<int, 18>& splitting_cells();

// For each of the 27 cells: what a finer node there refines of the node,
// bits 0-11 the edges it splits (numbering of cube_table.h) and bits 12-17
// the face (axis * 2 + side) across it; TransitionInput's split_edges and
// fine_faces are the union over the finer cells around.
const std::array<std::uint32_t, 27>& cell_splits();

// Everything a node needs to triangulate itself against finer neighbours.
struct TransitionInput {
  std::uint32_t inside;                          // bit p: lattice point p is inside
  const std::int32_t* edge_vertices;             // the node's 12 whole-edge vertices
  const std::int32_t* sub_edge_vertices;         // 48, in transition_sub_edges() order
  std::int32_t centre;                           // vertex the longest loop is fanned around
  std::uint8_t fine_faces;                       // bit axis*2+side: finer node across
  std::uint16_t split_edges;                     // bit e: finer node around edge e
  std::uint8_t straight_faces = 0;               // bit axis*2+side: see straight_faces()
};

// Bit axis*2+side is set where three of a node's crossings (its 12 whole-edge
// and 48 sub-edge vertices, -1 where none) on that face that one
// triangulation can hold together lie in line (in_line, core/types.h): a flat
// surface through the face, or one lying on it. A fan triangle with its three
// corners on such a face may have no area; where every apex has a triangle on
// some face, the triangulation takes one whose faces are not marked.
std::uint8_t straight_faces(const std::int32_t* edge_vertices, const std::int32_t* sub_edge_vertices,
                            const Vec3f* positions);

// Appends the node's triangles (outward, counter-clockwise) to `out`.
void triangulate_transition(const TransitionInput& in, std::vector<Triangle>* out);

// Starts loading what triangulate_transition will look up for `in`: called a
// few nodes ahead, it hides a cache miss per node.
void prefetch_transition(const TransitionInput& in);

// Starts loading a node's crossings (TransitionInput's two vertex arrays).
void prefetch_crossings(const std::int32_t* sub_edge_vertices, const std::int32_t* edge_vertices);

// How many triangles triangulate_transition appends for `in`.
int transition_triangle_count(const TransitionInput& in);

}  // namespace scan2lod
