// PCD files, read with PCL: organized clouds (width x height, NaN for no return)
// as range images, unorganized ones (height 1) as point clouds.
#pragma once

#include <scan2lod/acquisition/point_cloud_files.h>
#include <scan2lod/core/types.h>

#include <string>

namespace scan2lod {

// Reads an organized PCD as a range image. The cloud's VIEWPOINT becomes
// `pose` (sensor -> common frame) and the sensor sits at the scan frame's origin.
// Throws InputError for a missing file, an unorganized cloud (height 1),
// missing x/y/z fields or an empty cloud, and for a header or body PCL would
// misread (checked before PCL reads: a bad one can crash its reader).
RangeImage read_organized_pcd(const std::string& path, ScanPose* pose);

// Whether the PCD's header gives a height above 1 (checked as above; throws the same).
bool pcd_is_organized(const std::string& path);

// Reads any PCD as a point cloud: the finite points, placed by VIEWPOINT like
// read_organized_pcd; normals from normal_x/y/z (or nx/ny/nz) when all three
// are float fields; colours from rgb/rgba. A VIEWPOINT other than PCL's
// default (0 0 0 1 0 0 0) becomes the cloud's viewpoint.
PointCloud read_unorganized_pcd(const std::string& path);

}  // namespace scan2lod
