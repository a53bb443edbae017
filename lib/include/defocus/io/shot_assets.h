// What a shot reads besides its inputs: the images its aperture is drawn
// from and the colour config. A run reads them once, before its first
// frame, and hands them to every frame.
#pragma once

#include <memory>
#include <string>

#include <defocus/color/color.h>
#include <defocus/shot/shot.h>
#include <defocus/spread/aperture_images.h>

namespace defocus {

struct ShotAssets {
    ApertureImages aperture;
    /// The OpenColorIO config (see ColorManagement::load), or null when
    /// none was found and the shot names none.
    std::shared_ptr<const ColorManagement> color;
    std::string no_color;  ///< why there is no config
};

/// Reads the assets of `shot`. False with `error` naming the option, the
/// file and the problem.
bool read_shot_assets(const Shot& shot, ShotAssets& assets, std::string& error);

}  // namespace defocus
