#include "acquisition/load_inputs.h"

#include "acquisition/mesh_points.h"
#include "acquisition/organized_pcd.h"
#include "acquisition/range_grid_ply.h"
#include "core/error.h"
#include "core/parallel_jobs.h"
#include "io/mesh_file.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

namespace scan2lod {
namespace {

enum class Kind { conf, range_grid, pcd, mesh };

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

bool ply_has_range_grid(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  for (int n = 0; n < 10000 && std::getline(in, line); ++n) {
    if (line.rfind("element range_grid", 0) == 0) return true;
    if (line.rfind("end_header", 0) == 0) break;
  }
  return false;
}

Kind classify(const std::string& path) {
  std::error_code ec;  // the throwing overloads fail on e.g. an over-long name
  if (!std::filesystem::exists(path, ec)) throw InputError(path, "file does not exist");
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path, "is a folder; name its .conf or its scan files");
  std::string ext = lower_extension(path);
  if (ext == ".conf") return Kind::conf;
  if (ext == ".pcd") return Kind::pcd;
  if (ext == ".ply") return ply_has_range_grid(path) ? Kind::range_grid : Kind::mesh;
  if (ext == ".obj" || ext == ".off" || ext == ".stl") return Kind::mesh;
  throw InputError(path, "unknown input type '" + ext +
                             "': expected .conf, .ply, .pcd, .obj, .off or .stl");
}

struct Job {
  Kind kind;
  std::string file;
  ScanPose pose;
};

}  // namespace

OrientedPoints load_oriented_points(const std::vector<std::string>& inputs,
                                    const AcquisitionOptions& options,
                                    AcquisitionReport* report) {
  if (inputs.empty()) throw InputError("", "no input files given");
  std::vector<Job> jobs;
  for (const std::string& input : inputs) {
    Kind kind = classify(input);
    if (kind == Kind::conf) {
      for (ConfEntry& e : read_conf(input)) jobs.push_back({Kind::range_grid, e.file, e.pose});
    } else {
      jobs.push_back({kind, input, ScanPose{}});
    }
  }

  // Files are independent: read and orient them in parallel, merge in order.
  std::vector<OrientedPoints> parts(jobs.size());
  parallel_jobs(jobs.size(), options.threads, "reading inputs", [&](std::size_t i) {
    const Job& job = jobs[i];
    if (job.kind == Kind::range_grid) {
      parts[i] = range_image_to_points(read_range_grid_ply(job.file), job.pose, options.lattice);
    } else if (job.kind == Kind::pcd) {
      ScanPose pose;
      RangeImage image = read_organized_pcd(job.file, &pose);
      parts[i] = range_image_to_points(image, pose, options.lattice);
    } else {
      parts[i] = mesh_to_oriented_points(read_mesh(job.file));
    }
  });

  OrientedPoints points;
  AcquisitionReport local;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    if (parts[i].size() == 0)
      throw InputError(jobs[i].file, "holds no usable points (empty, or no sample has a "
                                     "valid neighbour to estimate a normal)");
    points.append(parts[i]);
    (jobs[i].kind == Kind::mesh ? local.meshes : local.range_images)++;
    local.files.push_back(jobs[i].file);
  }
  if (report) *report = std::move(local);
  return points;
}

}  // namespace scan2lod
