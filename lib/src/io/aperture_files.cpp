#include <defocus/io/aperture_files.h>

#include <defocus/io/image_input.h>
#include <defocus/shot/setting_words.h>

namespace defocus {

using OIIO::ImageBuf;

bool read_aperture_mask(const std::string& filename, double aspect, const Imath::V3d& luma,
                        MaskProfile& mask, std::string& error)
{
    ImageBuf image;
    if (!read_image_file(filename, "the aperture mask", image, error))
        return false;
    if (!mask.set_shape(image, aspect, luma, error)) {
        error = filename + ": " + error;
        return false;
    }
    return true;
}

bool read_psf_image(const std::string& filename, const Imath::V3d& luma, PsfImage& psf,
                    std::string& error)
{
    ImageBuf image;
    if (!read_image_file(filename, "the PSF image", image, error))
        return false;
    if (!psf.set_image(image, luma, error)) {
        error = filename + ": " + error;
        return false;
    }
    return true;
}

bool read_aperture_images(const Shot& shot, const Imath::V3d& luma, ApertureImages& images,
                          std::string& error)
{
    images = ApertureImages();
    const Aperture& aperture = shot.spread.aperture;
    if (aperture.shape == ApertureShape::Mask) {
        auto mask = std::make_shared<MaskProfile>();
        if (!read_aperture_mask(aperture.mask_file, aperture.aspect, luma, *mask, error)) {
            error = mention("aperture") + ": " + error;
            return false;
        }
        images.mask = std::move(mask);
    }
    if (!shot.spread.psf_image.empty()) {
        auto psf = std::make_shared<PsfImage>();
        if (!read_psf_image(shot.spread.psf_image, luma, *psf, error)) {
            error = mention("psf-image") + ": " + error;
            return false;
        }
        images.psf = std::move(psf);
    }
    return true;
}

}  // namespace defocus
