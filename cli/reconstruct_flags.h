// The reconstruction flags that `reconstruct` and `build` share, mapped one to
// one onto ReconstructOptions (reconstruct/marching_cubes.h).
#pragma once

#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/pipeline/build_model.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace scan2lod::cli {

// The inputs `reconstruct` and `build` read (acquisition/load_inputs.cpp, classify()).
inline const char* const kInputsHelp =
    "Range scans (a .conf, range-grid PLYs, organized PCDs), a point cloud (.ply .pcd .xyz .xyzn .xyzrgb .pts .las; "
    "normals estimated when it has none), or a mesh (.ply .obj .off .stl .vtp .glb .gltf)";

struct ReconstructFlags {
  ReconstructOptions options;
  std::string method = "planes";  // --distance, parsed by resolve()
  AcquisitionOptions acquisition; // --unregistered; threads set by resolve()

  std::string memory;    // --memory, e.g. 400M; empty: what the machine has available
  std::string work_dir;  // --work-dir; empty: OUTPUT.work
  int brick_cubes = 0;   // --brick-cubes; forces bricks

  // Sets options.distance.method from `method`; throws for an unknown name.
  const ReconstructOptions& resolve();
  // The build options these flags give, for an output at `output` (the work
  // folder's default lies beside it).
  BuildOptions build_options(const std::string& output);
  // Once the output is written: removes the work folder of a build in bricks
  // when it was the default one (a folder the user named is kept).
  void finished(const BuildReport& report, const BuildOptions& options) const;
};

// Adds -r/--resolution, --margin, --distance, --neighbours, --max-distance,
// --reach, --min-piece, --max-hole, --hole-rounds, --unregistered,
// --memory, --work-dir, --brick-cubes and -j/--threads to `cmd`,
// with the options' defaults shown in --help. `flags` must outlive parsing.
void add_reconstruct_flags(CLI::App* cmd, ReconstructFlags* flags);

// Throws InputError naming the inputs when the reconstruction found no
// surface, rather than writing an empty mesh or model; prints the
// reconstruction's warnings (e.g. a grid far finer than a mesh's vertices) to stderr.
void require_surface(const std::vector<std::string>& inputs, const Reconstruction& r, int resolution);

}  // namespace scan2lod::cli
