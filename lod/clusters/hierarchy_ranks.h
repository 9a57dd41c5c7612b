// The cluster hierarchy's blocks made on the ranks of an MPI job. Rank 0
// calls build_cluster_hierarchy() with ClusterOptions::sharing; it sends the
// mesh and the options to the others, which serve here. Block b of a pass is
// made by rank b mod N and sent to every rank, and every rank commits every
// block in block order, so that each holds the state the next pass starts
// from: the hierarchy rank 0 writes is the single process's, byte for byte.
// Only blocks are shared: a hierarchy small enough to be built whole, and
// the last passes that fit one block, run on rank 0 alone.
#pragma once

namespace scan2lod {

class WorkSharing;

// On a rank other than 0: waits for rank 0's build_cluster_hierarchy() (or
// release_hierarchy_ranks()) and makes its share of the blocks; returns when
// the blocked passes are over. `threads`: this rank's (0: every core).
void serve_cluster_hierarchy(WorkSharing& job, int threads);

// On rank 0, when it builds no cluster hierarchy: lets the others return from
// serve_cluster_hierarchy(). Nothing when `job` is null or of one rank.
void release_hierarchy_ranks(WorkSharing* job);

}  // namespace scan2lod
