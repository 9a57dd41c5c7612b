// What an LOD structure implements to stand behind the face (lod/lod_model.h):
// its levels (StructureLevels), its part of the model file (StructureSections,
// lod/model_sections.h) and its record in the table of registered structures
// (StructureKind). Everything generic walks that table: naming and presence,
// LevelExtractor, the model file's sections and `scan2lod info`. Each
// structure implements them in its own room (lod/octree/octree_structure.cpp
// and octree_sections.cpp, lod/clusters/cluster_structure.cpp and
// cluster_sections.cpp), and lod/registered_structures.cpp lists them.
// Internal to the library.
#pragma once

#include <scan2lod/lod/lod_model.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace scan2lod {

class StructureSections;

// Levels of one structure of one model. It may keep scratch space and cut
// tables between calls (a slider or a moving camera asks many times).
class StructureLevels {
 public:
  virtual ~StructureLevels() = default;
  // Chooses the level `request` asks for and says how into `cut` (its
  // priority, error or clusters), writing no triangles yet. Throws InputError
  // for a request the structure does not offer, saying what it offers.
  virtual void select(const LevelRequest& request, LevelCut* cut) = 0;
  // Writes the chosen level's triangles into `cut` (cleared), and its percent.
  virtual void emit(LevelCut* cut) = 0;
  // Triangles at full detail, and of the coarsest level offered.
  virtual std::int64_t full_triangles() const = 0;
  virtual std::int64_t coarsest_triangles() const = 0;
  // The triangle count of every level offered, in any order.
  virtual std::vector<std::int64_t> offered_triangles() const = 0;
  // Levels a view may colour, and per triangle of `cut` (the last emitted)
  // its level.
  virtual int levels() const = 0;
  virtual std::vector<std::uint8_t> triangle_levels(const LevelCut& cut) const = 0;
};

// What `scan2lod info` says of one structure: a paragraph and a table of its
// levels, and the same as JSON (under the structure's name; keys in README.md).
struct StructureInfo {
  std::string text;
  nlohmann::ordered_json json;
  // Keys of `json` repeated at the top level, for readers older than a
  // second structure.
  std::vector<std::string> top_level_keys;

  void say(const char* format, ...) __attribute__((format(printf, 2, 3)));
};

// One registered structure.
struct StructureKind {
  LodStructure id;
  const char* name;    // as the command line spells it: "octree"
  const char* phrase;  // in messages: "the octree"
  const char* level_noun;  // a level of it, in messages: "no octree level is ..."
  // The model-file format that first held it: structures lay out their
  // sections in the order they joined the format.
  std::uint32_t first_major;
  bool (*present)(const LodModel& model);
  // Requires present(model); the levels keep a reference to it.
  std::unique_ptr<StructureLevels> (*make_levels)(const LodModel& model);
  // Its part of one model file being written or read.
  std::unique_ptr<StructureSections> (*make_sections)();
  StructureInfo (*info)(const LodModel& model, const std::vector<double>& percents);
};

// Every registered structure, in the order a model's default is chosen (the
// first the model has) and the command line offers them.
const std::vector<const StructureKind*>& registered_structures();

// The same, in the order they joined the model-file format (first_major).
std::vector<const StructureKind*> structures_in_file_order();

const StructureKind& structure_kind(LodStructure id);

}  // namespace scan2lod
