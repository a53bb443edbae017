// Internal: what the data channels' spreads share: the quantities a layer
// carries as colour, how they are spread apart, and what the layers' alphas
// cover (see data_channels.h).
#pragma once

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <defocus/composite/defocus_layers.h>
#include <defocus/layers/layered_scene.h>

namespace defocus {

/// What one spread carries: quantities or objects' mattes, as R, G and B.
constexpr size_t per_spread = 3;

/// Fills up to per_spread quantities of a layer pixel.
using QuantityFill = std::function<void(int x, int y, float q[per_spread])>;

/// `layer` over `roi` with three quantities times its alpha as colour.
Layer quantity_layer(const Layer& layer, const OIIO::ROI& roi, const QuantityFill& fill,
                     int nthreads);

/// One layer's spread quantities: premultiplied float RGBA over what it lights.
using QuantitySink = std::function<void(size_t layer, const OIIO::ImageBuf& spread)>;

/// Everything the spreads share: the scene, how it is spread, and where.
struct Spreader {
    const LayeredScene& scene;
    const ReachOnly& reach;
    OutputWindow window;
    int nthreads;
    const std::function<bool(int done, int total)>& keep_going;
    int total = 0;  ///< spreads in all
    int done = 0;

    /// Spreads `layers` (quantity layers, back to front, made from the
    /// scene's layers `from`) apart, each handed to `sink` by its scene index.
    /// Thousands of IDs are hundreds of spreads: each first asks whether
    /// to go on ("cancelled" when not), saying how far the stage is. With
    /// `own_light`, each layer is spread with one aperture cell: its
    /// quantities and alpha are its own light alone, whatever passes in
    /// front of it through each part of the lens.
    bool spread(std::vector<Layer>&& layers, const std::vector<size_t>& from,
                const QuantitySink& sink, std::string& error, bool own_light = false);
};

/// Per output pixel, over the result's window: what the first spread of
/// the layers' alphas says about them.
struct Coverage {
    OIIO::ROI roi;
    std::vector<float> alpha;        ///< the data spread's composite alpha
    /// The largest share of any layer so far, and whose it is (-1: none);
    /// empty without Dominant channels, which alone ask for them.
    std::vector<float> best_weight;
    std::vector<int> best_layer;
    /// Each layer's spread alpha, over what it lights.
    std::vector<OIIO::ImageBuf> layer_alpha;

    size_t index(int x, int y) const
    {
        return size_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin);
    }

    /// The transmittance in front of layer `i` over row y, columns
    /// [x0, x1), into t.
    void transmittance(size_t i, int y, int x0, int x1, float* t) const
    {
        std::fill(t, t + (x1 - x0), 1.0f);
        for (size_t m = i + 1; m < layer_alpha.size(); ++m) {
            if (!layer_alpha[m].initialized())
                continue;
            const OIIO::ROI& r = layer_alpha[m].roi();
            const int begin = std::max(x0, r.xbegin), end = std::min(x1, r.xend);
            if (y < r.ybegin || y >= r.yend || begin >= end)
                continue;
            const float* a = static_cast<const float*>(layer_alpha[m].pixeladdr(begin, y));
            for (int x = begin; x < end; ++x)
                t[x - x0] *= 1.0f - a[x - begin];
        }
    }
};

}  // namespace defocus
