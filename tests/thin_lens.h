// The thin lens by brute force: the exact reference for sub-aperture
// compositing, on small synthetic stacks of layers.
#pragma once

#include <functional>
#include <vector>

#include <OpenImageIO/imagebuf.h>

namespace defocus_test {

/// A layer as the thin lens sees it: premultiplied RGBA, and the signed CoC
/// radius of each pixel (negative in front of the focus), over one window.
struct LensLayer {
    OIIO::ImageBuf color;
    OIIO::ImageBuf radius;
};

/// Whether the light through aperture point u = (ux, uy) reaches pixel
/// (x, y): the barrel's clip of the lens there (a cat's eye).
using LensClip = std::function<bool(double ux, double uy, int x, int y)>;

/// For each point u of a `samples` × `samples` grid over the aperture's
/// bounding square that lies in the unit disc, every layer's pixel s lands
/// at s + ρ(s)·u, split bilinearly over the four pixels around that point;
/// the layers (back to front) are composited there with "over", a layer's
/// coverage past 1 scaled back to 1 as the engine does; and each pixel's
/// composites are averaged over the points `clip` lets reach it (all
/// without one). Float RGBA over `window`.
OIIO::ImageBuf thin_lens(const std::vector<LensLayer>& back_to_front, const OIIO::ROI& window,
                         int samples = 48, const LensClip& clip = {});

/// PSNR in dB of `image` against `reference` over `roi` (R, G, B), the
/// peak being the reference's brightest value there.
double psnr_over(const OIIO::ImageBuf& image, const OIIO::ImageBuf& reference,
                 const OIIO::ROI& roi);

}  // namespace defocus_test
