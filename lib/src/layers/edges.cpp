#include <defocus/layers/edges.h>

#include <algorithm>
#include <cmath>
#include <new>

#include <OpenImageIO/parallel.h>

#include <defocus/layers/layered_scene.h>

#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// `image` over `grown` (which contains its window), each pixel outside
/// taking the value of the nearest pixel inside.
ImageBuf clamped_copy(const ImageBuf& image, const ROI& grown, int nthreads)
{
    const ROI inside = image.roi();
    ImageSpec spec = image.spec();
    spec.set_roi(grown);
    ImageBuf out(spec, InitializePixels::No);
    if (!out.localpixels())
        throw std::bad_alloc();  // callers check sizes first: this is the last guard
    const size_t pixel_bytes = spec.pixel_bytes();
    parallel_for(grown.ybegin, grown.yend, [&](int y) {
        const int sy = std::clamp(y, inside.ybegin, inside.yend - 1);
        for (int x = grown.xbegin; x < grown.xend; ++x) {
            const int sx = std::clamp(x, inside.xbegin, inside.xend - 1);
            std::copy_n(static_cast<const char*>(image.pixeladdr(sx, sy)), pixel_bytes,
                        static_cast<char*>(out.pixeladdr(x, y)));
        }
    }, by_rows(nthreads));
    return out;
}

}  // namespace

int extend_edges(LayeredScene& scene, const CircleOfConfusion& coc, EdgeMode mode, int nthreads)
{
    if (mode == EdgeMode::Black)
        return 0;
    const ImageSpec& s = scene.spec;
    const ROI data = s.roi();
    // Overscan past the display window on each side: left, right, top, bottom.
    const int overscan[4] = { s.full_x - data.xbegin, data.xend - (s.full_x + s.full_width),
                              s.full_y - data.ybegin, data.yend - (s.full_y + s.full_height) };
    int most = 0;
    for (size_t i = 0; i < scene.layers.size(); ++i) {
        Layer& layer = scene.layers[i];
        const LayerReport& r = scene.reports[i];
        if (r.pixels == 0)
            continue;
        // The last pixel a footprint reaches, and one more for antialiasing.
        const int reach = int(std::ceil(0.5 * std::max(std::abs(r.coc_min), std::abs(r.coc_max)))) + 1;
        const ROI own = layer.color.roi();
        const bool touches[4] = { own.xbegin <= data.xbegin, own.xend >= data.xend,
                                  own.ybegin <= data.ybegin, own.yend >= data.yend };
        int add[4];
        for (int side = 0; side < 4; ++side) {
            // A data window edge inside the display window bounds content
            // (a tight deep bounding box, say), not a render cut off by the
            // frame: nothing lies beyond it.
            const bool cut_off = overscan[side] >= 0;
            const int wanted = mode == EdgeMode::Extend ? reach
                               : cut_off                ? reach - overscan[side]
                                                        : 0;
            add[side] = touches[side] ? std::max(0, wanted) : 0;
            most = std::max(most, add[side]);
        }
        if (!add[0] && !add[1] && !add[2] && !add[3])
            continue;
        const ROI grown(own.xbegin - add[0], own.xend + add[1], own.ybegin - add[2],
                        own.yend + add[3]);
        // Where the blur is wide against the layer (a strip a pixel high
        // under a 512 px blur), what is repeated would outweigh what is
        // there: auto leaves it (a 400000x1 strip grew to 206 million
        // pixels, 7 GB).
        if (mode == EdgeMode::Auto && double(grown.npixels()) > 4.0 * double(own.npixels()))
            continue;
        layer.color = clamped_copy(layer.color, grown, nthreads);
        layer.depth = clamped_copy(layer.depth, grown, nthreads);
        scene.reports[i] = describe_layer(layer, coc, nthreads);
    }
    if (most > 0)
        sort_back_to_front(scene);
    return most;
}

}  // namespace defocus
