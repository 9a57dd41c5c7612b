// consumer MODEL.mco BUDGET OUT.glb TILES: loads a model, takes the finest
// level within BUDGET triangles from its default structure, writes it as
// glTF, writes the model's 3D Tiles tileset into the folder TILES, and prints
// "<structure> <triangles> <vertices> <tiles>".
#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/delivery/tileset.h>
#include <scan2lod/io/gltf_file.h>
#include <scan2lod/lod/model_file.h>

#include <cstdio>
#include <cstdlib>

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: consumer MODEL.mco BUDGET OUT.glb TILES\n");
    return 2;
  }
  int reports = 0;
  scan2lod::set_progress_sink([&](const std::string&, double, bool) { ++reports; });
  try {
    const scan2lod::LodModel model = scan2lod::load_model(argv[1]);
    const scan2lod::LodStructure structure = scan2lod::default_structure(model);
    scan2lod::LevelExtractor extractor(model, structure);
    const scan2lod::LevelCut& cut = extractor.extract(scan2lod::LevelRequest::at_triangles(std::atoll(argv[2])));
    const scan2lod::TriangleMesh mesh = scan2lod::compact_level(model, cut.triangles);
    scan2lod::write_gltf(argv[3], mesh);
    const scan2lod::TilesetReport tiles = scan2lod::write_tileset(model, argv[4]);
    std::printf("%s %zu %zu %zu\n", scan2lod::structure_name(structure), mesh.triangles.size(), mesh.positions.size(),
                tiles.tiles);
  } catch (const scan2lod::InputError& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
  return 0;
}
