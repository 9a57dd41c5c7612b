// Organized point clouds (.pcd with width x height, NaN for no return), read with PCL.
#pragma once

#include "core/types.h"

#include <string>

namespace scan2lod {

// Reads an organized PCD as a range image. The cloud's VIEWPOINT becomes
// `pose` (sensor -> common frame) and the sensor sits at the scan frame's origin.
// Throws InputError for a missing file, an unorganized cloud (height 1),
// missing x/y/z fields or an empty cloud, and for a header or body PCL would
// misread (checked before PCL reads: a bad one can crash its reader).
RangeImage read_organized_pcd(const std::string& path, ScanPose* pose);

}  // namespace scan2lod
