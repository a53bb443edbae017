// Reading the images an aperture is drawn from: a mask's shape and the
// hybrid method's PSF. A run reads them once, before its first frame.
#pragma once

#include <memory>
#include <string>

#include <defocus/shot/shot.h>
#include <defocus/spread/aperture_profile.h>
#include <defocus/spread/hybrid.h>

namespace defocus {

/// The shape of --aperture mask:FILE, squeezed by `aspect`. False with
/// `error` naming the file and the problem.
bool read_aperture_mask(const std::string& filename, double aspect, MaskProfile& mask,
                        std::string& error);

/// The PSF of the hybrid method. False with `error` naming the file and
/// the problem.
bool read_psf_image(const std::string& filename, PsfImage& psf, std::string& error);

/// The images a shot's settings name.
struct ApertureImages {
    std::shared_ptr<const MaskProfile> mask;  ///< a mask aperture's shape, else null
    std::shared_ptr<const PsfImage> psf;      ///< the hybrid method's PSF, else null
};

/// Reads the images `shot` names. False with `error` naming the option,
/// the file and the problem.
bool read_aperture_images(const Shot& shot, ApertureImages& images, std::string& error);

}  // namespace defocus
