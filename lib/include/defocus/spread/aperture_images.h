// The images an aperture is drawn from, once read (io/aperture_files.h).
#pragma once

#include <memory>

#include <defocus/spread/aperture_profile.h>
#include <defocus/spread/hybrid.h>

namespace defocus {

struct ApertureImages {
    std::shared_ptr<const MaskProfile> mask;  ///< a mask aperture's shape, else null
    std::shared_ptr<const PsfImage> psf;      ///< the hybrid method's PSF, else null
};

}  // namespace defocus
