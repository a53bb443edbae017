// Internal: small lights that a nearer layer cuts, continued behind it as
// the discs they are.
#pragma once

#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "layers/hole_map.h"
#include "util/float_pixels.h"

namespace defocus {

/// A small light that a nearer layer cuts (a lamp half behind a pole) ends
/// at the nearer layer's edge in a flat render, where the lens sees around
/// the edge to the whole disc. Each patch of seen pixels brighter than
/// `highlight`, up to 64 px across, that borders hidden pixels is taken
/// for a disc: a circle fitted to its rim away from the hole (Kåsa 1976),
/// then to how much of the light each seen pixel around it holds, whose
/// antialiased values place the edge to a fraction of a pixel (the rim's
/// pixel centres alone put a short arc's circle a pixel or more off). The
/// hidden pixels take the disc, antialiased, over what the light's seen
/// surroundings hold, out to as far again as its radius: the fill around
/// a light is otherwise a blur of the light itself. Lights whose rim draws
/// no circle that holds them are left to the fill.
class ContinuedLights {
public:
    /// Finds the lights of `color`'s pixels within `window` that border the
    /// hidden pixels of `holes`.
    ContinuedLights(const FloatPixels& color, const FloatPixels& depth, const HoleMap& holes,
                    const OIIO::ROI& window, float highlight, int nthreads);

    /// The continued light at hidden pixel (x, y): premultiplied R, G, B,
    /// A and the alpha-weighted depth; false where no light reaches.
    bool at(int x, int y, float value[5]) const;

    /// A pixel's coordinates.
    struct Pixel {
        int x, y;
    };

private:
    struct Light {
        double cx, cy, radius, reach;
        float light[5];   ///< the light's mean inside its rim
        float around[5];  ///< its seen surroundings' mean
    };
    struct Patch;

    bool hidden(int x, int y) const;
    /// Within two pixels of a hidden one along a row or column.
    bool beside_hole(int x, int y) const;
    /// Seen, and brighter than the highlight.
    bool bright(int x, int y) const;
    /// The disc `patch` draws; false where it draws none that holds it.
    bool fit(const Patch& patch, Light& light) const;

    const FloatPixels& m_color;
    const FloatPixels& m_depth;
    const HoleMap& m_holes;
    OIIO::ROI m_window;
    float m_highlight;
    std::vector<Light> m_lights;
    /// Per band of `band_rows` rows of the window, the lights reaching it.
    std::vector<std::vector<size_t>> m_bands;
    static constexpr int band_rows = 32;
};

}  // namespace defocus
