// Reading the images an aperture is drawn from: a mask's shape and the
// hybrid method's PSF. A run reads them once, before its first frame.
#pragma once

#include <memory>
#include <string>

#include <defocus/shot/shot.h>
#include <defocus/spread/aperture_images.h>

namespace defocus {

/// The shape of --aperture mask:FILE, squeezed by `aspect`, its luminance
/// weighted by `luma`. False with
/// `error` naming the file and the problem.
bool read_aperture_mask(const std::string& filename, double aspect, const Imath::V3d& luma,
                        MaskProfile& mask, std::string& error);

/// The PSF of the hybrid method. False with `error` naming the file and
/// the problem.
bool read_psf_image(const std::string& filename, const Imath::V3d& luma, PsfImage& psf,
                    std::string& error);

/// Reads the images `shot` names, their luminance weighted by `luma` (see
/// ColorManagement::luma). False with `error` naming the option, the file
/// and the problem.
bool read_aperture_images(const Shot& shot, const Imath::V3d& luma, ApertureImages& images,
                          std::string& error);

}  // namespace defocus
