// Whether a camera has a frame to project with: a view direction, and an up
// that gives a sideways axis. level_request() (lod/level_choice.h) asks this
// before a camera cut (lod/lod_model.h, LevelRequest::for_camera) for the
// command line's --camera and the Python package's camera= alike, so that a
// bad camera is refused by one rule with one message.
#pragma once

#include <scan2lod/lod/clusters/cluster_cut.h>

#include <string>

namespace scan2lod {

// Throws InputError, its message starting with `asker` (e.g. "--camera"),
// when the eye is the target, when up has no direction, or when up is
// parallel to the view direction; the message names the values given.
void require_camera_frame(const CameraView& camera, const std::string& asker);

}  // namespace scan2lod
