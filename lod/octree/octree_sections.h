// The octree's part of the model file (lod/model_sections.h). Internal.
#pragma once

#include <scan2lod/lod/model_sections.h>

#include <memory>

namespace scan2lod {

std::unique_ptr<StructureSections> octree_sections();

}  // namespace scan2lod
