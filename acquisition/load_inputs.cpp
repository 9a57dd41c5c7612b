#include <scan2lod/acquisition/load_inputs.h>

#include <scan2lod/acquisition/cloud_normals.h>
#include <scan2lod/acquisition/las_file.h>
#include <scan2lod/acquisition/mesh_points.h>
#include <scan2lod/acquisition/organized_pcd.h>
#include <scan2lod/acquisition/point_cloud_files.h>
#include <scan2lod/acquisition/range_grid_ply.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/parallel_jobs.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/io/file_extension.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/io/ply_header.h>

#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace scan2lod {
namespace {

enum class Kind { conf, range_grid, pcd, cloud, mesh };

enum class PlyKind { range_grid, mesh, cloud };

// A PLY with a range grid is a scan, one with faces a mesh, one with neither a point cloud.
// By line prefixes rather than io/ply_header.h: this rule picks the reader, and a
// header spaced oddly must keep going to the reader it went to.
PlyKind ply_kind(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  bool faces = false;
  for (int n = 0; n < 10000 && std::getline(in, line); ++n) {
    if (line.rfind("element range_grid", 0) == 0) return PlyKind::range_grid;
    if (line.rfind("element face", 0) == 0) {
      long long count = 0;
      faces |= std::sscanf(line.c_str(), "element face %lld", &count) == 1 && count > 0;
    }
    if (line.rfind("end_header", 0) == 0) break;
  }
  return faces ? PlyKind::mesh : PlyKind::cloud;
}

Kind classify(const std::string& path) {
  std::error_code ec;  // the throwing overloads fail on e.g. an over-long name
  if (!std::filesystem::exists(path, ec)) throw InputError(path, "file does not exist");
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path, "is a folder; name its .conf or its scan files");
  std::string ext = lower_extension(path);
  if (ext == ".conf") return Kind::conf;
  if (ext == ".pcd") return pcd_is_organized(path) ? Kind::pcd : Kind::cloud;
  if (ext == ".ply") {
    const PlyKind kind = ply_kind(path);
    return kind == PlyKind::range_grid ? Kind::range_grid : kind == PlyKind::mesh ? Kind::mesh : Kind::cloud;
  }
  if (ext == ".xyz" || ext == ".pts" || ext == ".xyzn" || ext == ".xyzrgb" || ext == ".las") return Kind::cloud;
  if (ext == ".laz") throw InputError(path, laz_refusal(path));
  if (ext == ".obj" || ext == ".off" || ext == ".stl" || ext == ".vtp" || ext == ".glb" || ext == ".gltf") return Kind::mesh;
  throw InputError(path, "unknown input type '" + ext +
                             "': expected .conf, .ply, .pcd, .xyz, .pts, .las, .obj, .off, .stl, .vtp, .glb or .gltf");
}

PointCloud read_point_cloud(const std::string& path, const Vec3d& origin) {
  const std::string ext = lower_extension(path);
  if (ext == ".las") return read_las(path, origin);
  if (ext == ".pcd") return read_unorganized_pcd(path);
  if (ext == ".ply") return read_point_cloud_ply(path);
  return read_point_cloud_text(path);
}

// The .conf beside the first scan that lists every one of the scans, if any.
std::string conf_listing(const std::vector<std::string>& scans) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path folder = fs::absolute(scans.front(), ec).parent_path();
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    if (lower_extension(it->path().string()) != ".conf") continue;
    std::vector<ConfEntry> entries;
    try {
      entries = read_conf(it->path().string());
    } catch (const InputError&) {
      continue;
    }
    bool all = true;
    for (const std::string& scan : scans) {
      bool listed = false;
      for (const ConfEntry& e : entries) listed |= fs::equivalent(e.file, scan, ec);
      all &= listed;
    }
    // Named in the form the user gave the scans (absolute or relative).
    if (all) return (fs::path(scans.front()).parent_path() / it->path().filename()).string();
  }
  return "";
}

// Range-grid PLYs hold no pose: merged as given they would not line up
// (10 % error and dozens of boundary loops on the bunny, silently).
void require_registration(const std::vector<std::string>& loose_scans, bool with_conf) {
  if (loose_scans.size() < 2 && !(with_conf && !loose_scans.empty())) return;
  std::string names;
  for (std::size_t i = 0; i < loose_scans.size() && i < 3; ++i) names += (i ? ", " : "") + loose_scans[i];
  if (loose_scans.size() > 3) names += " and " + std::to_string(loose_scans.size() - 3) + " more";
  const std::string conf = conf_listing(loose_scans);
  const std::string what =
      std::to_string(loose_scans.size()) + " range-grid scan" + (loose_scans.size() > 1 ? "s" : "") +
      " given without the .conf that places them in one frame" + (with_conf ? " (beside a .conf)" : "") +
      "; range-grid PLYs carry no pose, so merged as they are they would not line up. ";
  throw InputError(names, what + (conf.empty() ? "Give their .conf (a Stanford .conf with one bmesh line per scan)"
                                               : "Give " + conf + ", which places them,") +
                              " instead, or pass --unregistered if the scans already share one frame");
}

struct Job {
  Kind kind;
  std::string file;
  ScanPose pose;
  Vec3d origin = Vec3d::Zero();  // the inputs' common local origin (AcquisitionReport::origin)
};

// The local origin all inputs are shifted to: that of the first LAS input
// (acquisition/las_file.h), read from its header; zero without LAS inputs.
// One origin for all, so that tiles and other inputs keep their places.
Vec3d common_origin(const std::vector<Job>& jobs) {
  for (const Job& job : jobs)
    if (lower_extension(job.file) == ".las") return las_local_origin(read_las_header(job.file));
  return Vec3d::Zero();
}

// The files to read, in order, with their poses and the common origin; checks registration.
std::vector<Job> plan_jobs(const std::vector<std::string>& inputs, const AcquisitionOptions& options) {
  if (inputs.empty()) throw InputError("", "no input files given");
  std::vector<Job> jobs;
  std::vector<std::string> loose_scans;
  bool with_conf = false;
  for (const std::string& input : inputs) {
    Kind kind = classify(input);
    if (kind == Kind::conf) {
      with_conf = true;
      for (ConfEntry& e : read_conf(input)) jobs.push_back({Kind::range_grid, e.file, e.pose});
    } else {
      if (kind == Kind::range_grid) loose_scans.push_back(input);
      jobs.push_back({kind, input, ScanPose{}});
    }
  }
  if (!options.unregistered) require_registration(loose_scans, with_conf);
  const Vec3d origin = common_origin(jobs);
  for (Job& job : jobs) job.origin = origin;
  return jobs;
}

// Positions relative to `from` made relative to `to` (both points of the
// inputs' frame), in double: a file in the inputs' own frame has from = 0.
void move_origin(std::vector<Vec3f>* positions, const Vec3d& from, const Vec3d& to) {
  if (from == to) return;
  const Vec3d shift = from - to;
  for (Vec3f& p : *positions) p = (p.cast<double>() + shift).cast<float>();
}

// One file's oriented points about the common origin; `estimated`: its
// normals were estimated.
OrientedPoints read_job(const Job& job, const AcquisitionOptions& options, int threads, bool* estimated,
                        std::vector<std::string>* warnings) {
  *estimated = false;
  OrientedPoints points;
  if (job.kind == Kind::range_grid) {
    const RangeImage image = read_range_grid_ply(job.file);
    *warnings = image.warnings;
    points = range_image_to_points(image, job.pose, options.lattice);
  } else if (job.kind == Kind::pcd) {
    ScanPose pose;
    RangeImage image = read_organized_pcd(job.file, &pose);
    points = range_image_to_points(image, pose, options.lattice);
  } else if (job.kind == Kind::cloud) {
    PointCloud cloud = read_point_cloud(job.file, job.origin);
    *warnings = cloud.warnings;
    *estimated = cloud.normals.empty();
    move_origin(&cloud.positions, cloud.origin, job.origin);
    CloudNormalOptions cloud_options = options.cloud;
    cloud_options.threads = threads;
    return cloud_to_oriented_points(cloud, cloud_options);
  } else {
    points = mesh_to_oriented_points(read_mesh(job.file));
    if (lower_extension(job.file) == ".ply") {
      const std::string skipped = ply_header_warning(job.file);
      if (!skipped.empty()) warnings->push_back(skipped);
    }
  }
  move_origin(&points.positions, Vec3d::Zero(), job.origin);
  return points;
}

// Reads jobs [from, to) in parallel (one alone gets every core for its own
// parallel work) and hands them to `take` in order.
void read_jobs(const std::vector<Job>& jobs, std::size_t from, std::size_t to, const AcquisitionOptions& options,
               AcquisitionReport* report, Progress* progress, const std::function<void(OrientedPoints&&)>& take) {
  const std::size_t count = to - from;
  std::vector<OrientedPoints> parts(count);
  std::vector<std::uint8_t> estimated(count, 0);
  std::vector<std::vector<std::string>> warnings(count);
  auto read = [&](std::size_t i, int threads) {
    bool e = false;
    parts[i] = read_job(jobs[from + i], options, threads, &e, &warnings[i]);
    estimated[i] = e;
  };
  if (count == 1) read(0, options.threads), progress->advance();
  else parallel_jobs(count, options.threads, progress, [&](std::size_t i) { read(i, 1); });
  for (std::size_t i = 0; i < count; ++i) {
    const Job& job = jobs[from + i];
    if (parts[i].size() == 0)
      throw InputError(job.file, "holds no usable points (empty, or no sample has a "
                                 "valid neighbour to estimate a normal)");
    if (job.kind == Kind::cloud) ++report->clouds, report->clouds_estimated += estimated[i];
    else (job.kind == Kind::mesh ? report->meshes : report->range_images)++;
    report->files.push_back(job.file);
    report->warnings.insert(report->warnings.end(), warnings[i].begin(), warnings[i].end());
    take(std::move(parts[i]));
  }
}

}  // namespace

OrientedPoints load_oriented_points(const std::vector<std::string>& inputs,
                                    const AcquisitionOptions& options,
                                    AcquisitionReport* report) {
  const std::vector<Job> jobs = plan_jobs(inputs, options);
  // Files are independent: read and orient them in parallel, merge in order.
  std::vector<OrientedPoints> parts;
  AcquisitionReport local;
  Progress progress("reading inputs", jobs.size());
  read_jobs(jobs, 0, jobs.size(), options, &local, &progress,
            [&](OrientedPoints&& part) { parts.push_back(std::move(part)); });
  progress.finish();
  OrientedPoints points = merge_parts(&parts);
  local.origin = jobs.front().origin;
  if (report) *report = std::move(local);
  return points;
}

OrientedPoints merge_parts(std::vector<OrientedPoints>* parts) {
  OrientedPoints points;
  std::size_t total = 0;
  bool colors = false, confidence = false, spacing = false;
  for (const OrientedPoints& part : *parts) {
    total += part.size();
    colors |= part.has_colors(), confidence |= !part.confidence.empty(), spacing |= !part.spacing.empty();
  }
  // Merged once into arrays of their final size: growing them part by part
  // would copy (and page-fault) them again at every doubling.
  points.positions.reserve(total);
  points.normals.reserve(total);
  if (colors) points.colors.reserve(total);
  if (confidence) points.confidence.reserve(total);
  if (spacing) points.spacing.reserve(total);
  for (OrientedPoints& part : *parts) {
    points.append(part);
    part = OrientedPoints{};  // freed for the next part's copy to reuse
  }
  parts->clear();
  return points;
}

void stream_oriented_points(const std::vector<std::string>& inputs, const AcquisitionOptions& options,
                            AcquisitionReport* report,
                            const std::function<void(OrientedPoints&&, double read_share)>& take,
                            InputShare share) {
  std::vector<Job> jobs = plan_jobs(inputs, options);
  const Vec3d origin = jobs.front().origin;
  std::vector<double> bytes(jobs.size() + 1, 0.0);  // of the files before each job
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(jobs[i].file, ec);
    bytes[i + 1] = bytes[i] + (ec ? 0.0 : double(size));
  }
  if (share.parts > 1) {
    // A file goes to the part its middle byte falls in: contiguous runs,
    // each near its part of the bytes, whatever the sizes.
    std::size_t from = jobs.size(), to = 0;
    for (std::size_t i = 0; i < jobs.size(); ++i) {
      const double middle = bytes.back() > 0 ? 0.5 * (bytes[i] + bytes[i + 1]) / bytes.back()
                                             : (double(i) + 0.5) / double(jobs.size());
      if (std::min(share.parts - 1, int(middle * share.parts)) == share.part) from = std::min(from, i), to = i + 1;
    }
    if (from >= to) from = to = 0;
    jobs = std::vector<Job>(jobs.begin() + std::ptrdiff_t(from), jobs.begin() + std::ptrdiff_t(to));
    bytes = std::vector<double>(bytes.begin() + std::ptrdiff_t(from), bytes.begin() + std::ptrdiff_t(to) + 1);
    const double before = bytes.front();
    for (double& b : bytes) b -= before;
  }
  std::size_t taken = 0;
  auto take_next = [&](OrientedPoints&& part) {
    ++taken;
    take(std::move(part), bytes.back() > 0 ? bytes[taken] / bytes.back() : double(taken) / double(jobs.size()));
  };
  AcquisitionReport local;
  AcquisitionReport& r = report ? *report : local;
  r = AcquisitionReport();
  r.origin = origin;
  // As many files at once as there are cores: in memory are those only.
  const std::size_t window = std::size_t(std::max(1, options.threads > 0 ? options.threads : omp_get_max_threads()));
  Progress progress("reading inputs", jobs.size());
  for (std::size_t from = 0; from < jobs.size(); from += window)
    read_jobs(jobs, from, std::min(jobs.size(), from + window), options, &r, &progress, take_next);
  progress.finish();
}

}  // namespace scan2lod
