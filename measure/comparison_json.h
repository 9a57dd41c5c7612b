// A surface comparison as one JSON object: what `scan2lod compare --json`
// prints and what the Python package's compare() returns as a dict, so that
// the two name every figure alike.
//
//   {"a_to_b": {"mean", "rms", "p95", "max", "samples"}, "b_to_a": {...},
//    "diagonal", "a": {topology}, "b": {topology}}
// with the topology's keys those of MeshTopology (measure/topology.h).
#pragma once

#include <scan2lod/measure/surface_distance.h>

#include <nlohmann/json.hpp>

namespace scan2lod {

nlohmann::json distance_stats_json(const DistanceStats& stats);
nlohmann::json topology_json(const MeshTopology& topology);
nlohmann::json comparison_json(const SurfaceComparison& comparison);

}  // namespace scan2lod
