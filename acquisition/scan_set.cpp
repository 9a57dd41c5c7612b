#include <scan2lod/acquisition/scan_set.h>

#include <scan2lod/acquisition/organized_pcd.h>
#include <scan2lod/acquisition/range_grid_ply.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/parallel_jobs.h>
#include <scan2lod/io/file_extension.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <set>

namespace scan2lod {

std::vector<PlacedScan> read_scan_set(const std::vector<std::string>& inputs, int threads) {
  struct Job {
    std::string file;
    ScanPose pose;
    bool pcd;
  };
  std::vector<Job> jobs;
  for (const std::string& input : inputs) {
    const std::string ext = lower_extension(input);
    if (ext == ".conf") {
      for (ConfEntry& e : read_conf(input)) jobs.push_back({e.file, e.pose, false});
    } else if (ext == ".ply" || ext == ".pcd") {
      jobs.push_back({input, ScanPose{}, ext == ".pcd"});
    } else {
      throw InputError(input, "not a scan: expected a .conf, a range-grid .ply or an organized .pcd");
    }
  }
  if (jobs.empty()) throw InputError("", "no scans given");
  std::vector<PlacedScan> scans(jobs.size());
  parallel_jobs(jobs.size(), threads, "reading scans", [&](std::size_t i) {
    if (jobs[i].pcd) {
      scans[i].image = read_organized_pcd(jobs[i].file, &scans[i].pose);
    } else {
      scans[i].image = read_range_grid_ply(jobs[i].file);
      scans[i].pose = jobs[i].pose;
    }
  });
  return scans;
}

void write_scan_set(const std::string& dir, const std::vector<PlacedScan>& scans,
                    const std::string& conf_name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError(dir, "cannot create the output folder: " + ec.message());
  std::vector<ConfEntry> entries;
  std::set<std::string> used;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    std::string stem = fs::path(scans[i].image.source).stem().string();
    // The .conf is whitespace-separated: keep names to a safe alphabet.
    for (char& ch : stem)
      if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_' && ch != '.') ch = '_';
    if (stem.empty()) {
      char name[32];
      std::snprintf(name, sizeof name, "scan_%03zu", i);
      stem = name;
    }
    std::string name = stem + ".ply";
    for (int k = 2; used.count(name); ++k) name = stem + "_" + std::to_string(k) + ".ply";
    used.insert(name);
    const std::string file = (fs::path(dir) / name).string();
    write_range_grid_ply(file, scans[i].image);
    entries.push_back({file, scans[i].pose});
  }
  write_conf((fs::path(dir) / conf_name).string(), entries);
}

}  // namespace scan2lod
