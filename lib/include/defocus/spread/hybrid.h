// The hybrid method (Kosloff, Tao & Barsky 2009, sec. 4.2): the pixels whose
// bokeh is visible, bright highlights against their surroundings, are
// spread directly with a PSF image that carries intensity (a real lens's
// bright rim, onion rings, cat's eye); all others take the fast filter.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebuf.h>

#include <defocus/spread/footprint.h>

namespace defocus {

/// A point spread function given as an image: its luminance, spanning the
/// CoC's diameter, scaled to each pixel's CoC radius.
class PsfImage {
public:
    /// The PSF drawn in `image`: its luminance, R, G and B weighted by
    /// `luma` (see ColorManagement::luma). False with `error` saying why
    /// (read the file with read_psf_image).
    bool set_image(const OIIO::ImageBuf& image, const Imath::V3d& luma, std::string& error);

    /// The footprint for CoC radius r: the image resampled (bilinearly)
    /// over [-r, r]², normalised to sum to 1. Below a pixel, the pixel.
    Footprint footprint(double r) const;

private:
    int m_width = 0, m_height = 0;
    std::vector<float> m_luma;
    float sample(double u, double v) const;  ///< u, v in [0, 1]
};

/// Which pixels are highlights whose bokeh is visible: those with CoC
/// radius of at least a pixel whose luminance exceeds `threshold` times the
/// mean luminance over the square of their CoC diameter around them.
struct HighlightTest {
    double threshold = 0.0;  ///< 0: none
    /// The weights of R, G and B in luminance, in the pixels' colour space
    /// (see ColorManagement::luma).
    Imath::V3d luma { 0.0, 0.0, 0.0 };
};

/// The pixels of premultiplied RGBA `color` that pass `test` (the means
/// from a summed-area table, so each costs constant time). One byte per
/// pixel of color's data window, row by row: 1 where selected.
std::vector<uint8_t> visible_bokeh(const OIIO::ImageBuf& color, const OIIO::ImageBuf& radius,
                                   const HighlightTest& test, int nthreads = 0);

}  // namespace defocus
