#include <scan2lod/delivery/tileset.h>

#include <scan2lod/core/error.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <vector>

#include <unistd.h>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A 3D Tiles box: centre and three half axes, here along the model's axes,
// widened by `pad` on every side (and never flat, which a viewer cannot cull).
json box_volume(const Aabb& box, double pad) {
  const Vec3d lo = box.min.cast<double>(), hi = box.max.cast<double>();
  const Vec3d c = (lo + hi) * 0.5, h = ((hi - lo) * 0.5).array() + pad;
  const std::vector<double> box12 = {c.x(), c.y(), c.z(), h.x(), 0, 0, 0, h.y(), 0, 0, 0, h.z()};
  json volume;
  volume["box"] = box12;
  return volume;
}

std::string tile_uri(const Tile& t) { return "tiles/" + t.name + ".glb"; }

// A tile's box is padded more than its content's, and a parent's more than its
// children's, so that rounding never puts one outside the box that holds it.
json tile_json(const TileTree& tree, int index, double pad) {
  const Tile& t = tree.tiles[std::size_t(index)];
  json j;
  j["boundingVolume"] = box_volume(t.subtree_box, pad * (2 + std::max(0, 64 - t.depth)));
  j["geometricError"] = t.geometric_error;
  if (index == 0) j["refine"] = "REPLACE";  // inherited by every tile below
  if (t.has_content()) j["content"] = {{"uri", tile_uri(t)}, {"boundingVolume", box_volume(t.content_box, pad)}};
  if (!t.children.empty()) {
    j["children"] = json::array();
    for (int c : t.children) j["children"].push_back(tile_json(tree, c, pad));
  }
  return j;
}

void write_file(const fs::path& path, const void* data, std::size_t size, const std::string& dir) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InputError(dir, "cannot create " + path.filename().string());
  out.write(static_cast<const char*>(data), std::streamsize(size));
  out.close();
  if (out.fail()) throw InputError(dir, "writing " + path.filename().string() + " failed (disk full?)");
}

// Refuses a destination that is not a folder, or a folder that holds
// something besides a tileset (replacing it would delete the user's files),
// or that holds the model itself.
void check_destination(const fs::path& dir, const std::string& source) {
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (!fs::exists(status)) return;
  if (!fs::is_directory(status)) throw InputError(dir.string(), "exists and is not a folder; a tileset is a folder");
  if (!fs::is_empty(dir, ec) && !fs::exists(dir / "tileset.json"))
    throw InputError(dir.string(), "is a folder that holds no tileset.json; refusing to replace it");
  if (!source.empty()) {
    const fs::path model = fs::weakly_canonical(source, ec), folder = fs::weakly_canonical(dir, ec);
    const auto mismatch = std::mismatch(folder.begin(), folder.end(), model.begin(), model.end());
    if (mismatch.first == folder.end())
      throw InputError(dir.string(), "holds the model " + source + "; replacing the folder would delete it");
  }
}

struct Staging {
  fs::path path;
  bool done = false;
  ~Staging() {
    if (done) return;
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

// Writes each tile's .glb as the planner hands its content out, keeping only
// the report's figures.
struct TileFiles {
  const fs::path& folder;
  const TilesetOptions& options;
  const std::string& dir;
  TilesetReport* report;
  double seconds = 0;  // spent in write(), within plan_tiles

  void write(const TileTree& tree, std::size_t index, const TileContent& content) {
    const auto start = std::chrono::steady_clock::now();
    const Tile& t = tree.tiles[index];
    // The grid depends on the bounds alone, which are final before any tile.
    const TileGlb glb = tile_glb(content.vertices, content.triangles, position_grid(tree.bounds), options.glb);
    write_file(folder / tile_uri(t), glb.bytes.data(), glb.bytes.size(), dir);
    ++report->content_tiles;
    report->bytes += glb.bytes.size();
    report->largest_tile_bytes = std::max<std::uint64_t>(report->largest_tile_bytes, glb.bytes.size());
    report->triangles += t.triangle_count;
    if (index == 0) report->root_triangles = t.triangle_count;
    else report->largest_tile_triangles = std::max(report->largest_tile_triangles, t.triangle_count);
    seconds += seconds_since(start);
  }
};

}  // namespace

float tileset_quantization_step(const TileTree& tree, const TileGlbOptions& options) {
  return options.quantize ? position_grid(tree.bounds).step() : 0.f;
}

std::string tileset_json(const TileTree& tree, const Vec3d& origin, float quantization_step,
                         const std::string& generator) {
  json j;
  j["asset"] = {{"version", "1.1"}, {"generator", generator}};
  j["geometricError"] = std::max(double(tree.bounds.diagonal()), double(tree.tiles[0].geometric_error));
  // One pad for every box, so that a content box never pokes out of its tile's.
  const double pad = std::max(double(quantization_step), 1e-6 * tree.bounds.diagonal() + 1e-12);
  json root = tile_json(tree, 0, pad);
  if (origin != Vec3d::Zero()) {
    // Column-major, as 3D Tiles stores a tile's transform.
    const std::vector<double> transform = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, origin.x(), origin.y(), origin.z(), 1};
    json ordered;
    ordered["transform"] = transform;
    for (auto& [key, value] : root.items()) ordered[key] = value;
    root = ordered;
  }
  j["root"] = root;
  return j.dump(1);
}

TilesetReport write_tileset(const LodModel& model, const std::string& dir, const TilesetOptions& options,
                            const std::string& source) {
  if (!model.origin.allFinite()) throw InputError(source, "the model's origin is not a finite point");
  const fs::path target = fs::path(dir).lexically_normal();
  if (target.empty() || target.filename().empty() || target.filename() == "." || target.filename() == "..")
    throw InputError(dir, "name a folder for the tileset");
  check_destination(target, source);
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) throw InputError(dir, "the folder " + parent.string() + " does not exist");
  Staging staging{parent / ("." + target.filename().string() + ".partial-" + std::to_string(::getpid()))};
  fs::remove_all(staging.path, ec);
  if (!fs::create_directories(staging.path / "tiles", ec) || ec)
    throw InputError(dir, "cannot create the folder " + staging.path.string() + ": " + ec.message());

  // Each tile is written as soon as it is planned, so that no tile's
  // triangles outlive it.
  TilesetReport report;
  auto start = std::chrono::steady_clock::now();
  TileFiles files{staging.path, options, dir, &report};
  TileOptions tile_options = options.tiles;
  if (options.progress) tile_options.progress = [&](double f) { options.progress("write", f); };
  const TileTree tree =
      plan_tiles(model, tile_options, source,
                 [&files](const TileTree& t, std::size_t i, const TileContent& c) { files.write(t, i, c); });
  report.plan_seconds = seconds_since(start) - files.seconds;

  start = std::chrono::steady_clock::now();
  for (const Tile& t : tree.tiles) {
    ++report.tiles;
    report.depth = std::max(report.depth, t.depth);
    report.leaves += t.leaf();
  }
  report.root_error = tree.tiles[0].geometric_error;
  const std::string text = tileset_json(tree, model.origin, tileset_quantization_step(tree, options.glb),
                                        options.glb.generator);
  write_file(staging.path / "tileset.json", text.data(), text.size(), dir);
  report.bytes += text.size();
  if (options.add_files) options.add_files(staging.path.string());

  // Into place: an old tileset moves aside first and goes once the new one is there.
  const fs::path old = parent / ("." + target.filename().string() + ".old-" + std::to_string(::getpid()));
  const bool replacing = fs::exists(target, ec);
  if (replacing) {
    fs::rename(target, old, ec);
    if (ec) throw InputError(dir, "cannot move the old tileset aside: " + ec.message());
  }
  fs::rename(staging.path, target, ec);
  if (ec) {
    std::error_code back;
    if (replacing) fs::rename(old, target, back);
    throw InputError(dir, "cannot put the tileset in place: " + ec.message());
  }
  staging.done = true;
  if (replacing) fs::remove_all(old, ec);
  report.write_seconds = files.seconds + seconds_since(start);
  return report;
}

}  // namespace scan2lod
