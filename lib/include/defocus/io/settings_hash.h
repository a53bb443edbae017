// A fingerprint of the settings a frame is rendered with, recorded in each
// output (defocus:settingsHash) so that a rerun can tell a frame already
// written with the same settings from one to render again.
#pragma once

#include <string>

#include <defocus/shot/shot.h>

namespace defocus {

/// 16 hex digits over the defocus version, the shot's inputs (as absolute
/// paths), the value of every setting (given or defaulted; paths
/// absolute), the frame, and the frame it reads when it holds another's
/// inputs (source_frame). The frame list and the memory limit are left
/// out: they do not change a frame's pixels. The same settings give the
/// same hash however they were given (options, a .dof in any key order,
/// the Python module).
std::string settings_hash(const Shot& shot, int frame);

}  // namespace defocus
