#include "acquisition/organized_pcd.h"

#include "core/error.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <Eigen/Geometry>

#include <cstring>
#include <filesystem>
#include <limits>

namespace scan2lod {

RangeImage read_organized_pcd(const std::string& path, ScanPose* pose) {
  if (!std::filesystem::exists(path)) throw InputError(path, "file does not exist");
  pcl::PCLPointCloud2 cloud;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int pcd_version = 0;
  pcl::PCDReader reader;
  if (reader.read(path, cloud, origin, orientation, pcd_version, 0) < 0)
    throw InputError(path, "PCL could not parse the PCD file (bad header or truncated data)");
  if (cloud.width == 0 || cloud.height == 0) throw InputError(path, "the cloud is empty");
  if (cloud.height == 1)
    throw InputError(path, "the cloud is not organized (height 1); a range image needs "
                           "width x height with NaN for no return");
  const pcl::PCLPointField *fx = nullptr, *fy = nullptr, *fz = nullptr, *frgb = nullptr;
  for (const auto& f : cloud.fields) {
    if (f.datatype != pcl::PCLPointField::FLOAT32 && f.name != "rgba") continue;
    if (f.name == "x") fx = &f;
    if (f.name == "y") fy = &f;
    if (f.name == "z") fz = &f;
    if (f.name == "rgb" || f.name == "rgba") frgb = &f;
  }
  if (!fx || !fy || !fz) throw InputError(path, "the cloud needs float fields x, y and z");

  RangeImage image;
  image.cols = int(cloud.width);
  image.rows = int(cloud.height);
  image.source = path;
  image.viewpoint = Vec3f::Zero();
  const std::size_t n = std::size_t(cloud.width) * cloud.height;
  image.points.resize(n);
  if (frgb) image.colors.resize(n);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::size_t valid = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* src = &cloud.data[i * cloud.point_step];
    Vec3f p;
    std::memcpy(&p.x(), src + fx->offset, 4);
    std::memcpy(&p.y(), src + fy->offset, 4);
    std::memcpy(&p.z(), src + fz->offset, 4);
    if (p.allFinite()) ++valid;
    else p = Vec3f(nan, nan, nan);
    image.points[i] = p;
    if (frgb) {
      std::uint32_t packed;
      std::memcpy(&packed, src + frgb->offset, 4);
      image.colors[i] = Rgb{std::uint8_t(packed >> 16), std::uint8_t(packed >> 8), std::uint8_t(packed)};
    }
  }
  if (valid == 0) throw InputError(path, "the cloud has no finite points");
  if (pose) {
    pose->rotation = orientation.normalized().toRotationMatrix();
    pose->translation = origin.head<3>();
  }
  return image;
}

}  // namespace scan2lod
