// A chain of levels for delivery: several levels of one structure of one
// loaded model, taken in one pass, over one compacted vertex set that every
// level indexes (what glTF's MSFT_lod stores, io/gltf_file.h), with the share
// of the screen below which each level gives way to the next.
//
// Screen coverage follows from a level's object-space error e and the model's
// bounding-box diagonal D: seen at d pixels across on a screen H pixels high,
// the error spans e * d / D pixels, so a level is good while d <= p * D / e
// for a pixel tolerance p. Coverage is the screen share (d / H)^2 of the
// object's square bound, as Babylon.js measures MSFT_screencoverage. The
// cluster hierarchy gives e (its cut's error bound); the octree has no error
// bound, and its level's mean edge length over 4 stands in for one.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/lod/lod_model.h>

#include <string>
#include <vector>

namespace scan2lod {

struct ChainOptions {
  double pixel_error = 1;    // p: largest error on screen, in pixels
  int screen_height = 1080;  // H
};

struct ChainLevel {
  std::string name;              // e.g. "LOD2"
  LevelCut cut;                  // triangles index LevelChain::vertices
  double error = 0;              // e: the error bound, or the octree's stand-in
  double screen_coverage = 0;    // drawn from this screen share up (0 for the coarsest)
  std::string shortfall;         // budget_shortfall's sentence, or empty
};

struct LevelChain {
  LodStructure structure = LodStructure::kClusters;
  TriangleMesh vertices;          // positions, normals, colours; no triangles
  std::vector<ChainLevel> levels;  // finest first
};

// The level `request` asks of `extractor`, for writing out: throws
// InputError (naming `source`) for a request the structure does not offer, a
// level with no triangles, or a --triangles budget below the coarsest level
// (which the extractor answers with that coarsest level).
const LevelCut& extract_level_to_deliver(LevelExtractor* extractor, const LevelRequest& request,
                                         const std::string& source);

// Where `cut` answered a triangle budget that no offered level meets within
// 10 % (one structure's levels step over it): a sentence saying so, with the
// levels on either side and the one taken; empty otherwise.
std::string budget_shortfall(const LevelExtractor& extractor, const LevelRequest& request, const LevelCut& cut);

// Takes `requests` from `structure` of `model`, orders them finest first and
// compacts the vertices they use. Throws InputError (naming `source`) for a
// request the structure does not offer or one that gives no triangles.
LevelChain extract_chain(const LodModel& model, LodStructure structure, const std::vector<LevelRequest>& requests,
                         const std::string& source, const ChainOptions& options = {});

// Level `i` of `chain` as a self-contained mesh (only the vertices it uses).
TriangleMesh level_mesh(const LevelChain& chain, std::size_t i);

}  // namespace scan2lod
