// The hybrid method (Kosloff, Tao & Barsky 2009, sec. 4.2): the pixels whose
// bokeh is visible, bright highlights against their surroundings, are
// spread directly with a PSF image that carries intensity (a real lens's
// bright rim, onion rings, cat's eye); all others take the fast filter.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <defocus/spread/footprint.h>

namespace defocus {

/// A point spread function given as an image: its luminance, spanning the
/// CoC's diameter, scaled to each pixel's CoC radius.
class PsfImage {
public:
    /// The PSF drawn in `image` (its luminance). False with `error` saying
    /// why (read the file with read_psf_image).
    bool set_image(const OIIO::ImageBuf& image, std::string& error);

    /// The footprint for CoC radius r: the image resampled (bilinearly)
    /// over [-r, r]², normalised to sum to 1. Below a pixel, the pixel.
    Footprint footprint(double r) const;

private:
    int m_width = 0, m_height = 0;
    std::vector<float> m_luma;
    float sample(double u, double v) const;  ///< u, v in [0, 1]
};

/// The pixels of premultiplied RGBA `color` whose bokeh is visible: those
/// with CoC radius of at least a pixel whose luminance exceeds `threshold`
/// times the mean luminance over the square of their CoC diameter around
/// them (from a summed-area table, so each costs constant time). One byte
/// per pixel of color's data window, row by row: 1 where selected.
std::vector<uint8_t> visible_bokeh(const OIIO::ImageBuf& color, const OIIO::ImageBuf& radius,
                                double threshold, int nthreads = 0);

}  // namespace defocus
