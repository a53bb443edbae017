// Internal: the spreads of a frame's layers, each set up when it is
// composited and freed after, as defocus_layers() composites them.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <defocus/layers/layered_scene.h>
#include <defocus/optics/camera.h>

#include "spread/spread_plan.h"
#include "util/float_pixels.h"

namespace defocus {

/// The channels one spread of a layer composites as they are (`colour`,
/// `alpha`), and whether it also composites red and blue magnified. Under
/// axial chromatic aberration a layer is spread twice, green with its CoC
/// and red and blue with theirs (CocChannel), each pass composited on its
/// own spread alpha, so that each colour is occluded as its own blur says;
/// the frame's alpha is green's. A magnified pass (lateral) is also kept
/// whole, and its red and blue composited magnified, each by its own
/// factor; without axial aberration, that is the one pass, its green and
/// alpha composited as they are.
struct ChannelPass {
    CocChannel coc;
    bool colour[3];
    bool alpha;
    bool magnified = false;
};

/// The passes a camera spreads each layer in.
std::vector<ChannelPass> channel_passes(const Camera& camera);

/// One spread of a layer, in the channels of a pass. `spread.apart` also
/// holds an engine's spread that is composited magnified.
struct LayerPass {
    ChannelPass channels;
    PassSpread spread;
};

/// A layer ready to composite: its float pixels and its passes.
struct LayerSpreads {
    FloatPixels color_pixels;
    std::vector<LayerPass> passes;
};

/// A layer's pass that can land on a black frame: stored rather than
/// composited, so that only the frame beyond its reach is cleared first.
/// That is its only pass, when the engine spreads it unmagnified; null
/// otherwise.
const LayerPass* storable_pass(const LayerSpreads& layer);

/// A frame's layers and their spreads: each layer's radii and spreads set
/// up when first asked for, and freed once composited. Set up one at a
/// time as they are composited, only one layer's radii and survey are held
/// at once (a 4K frame's four held together took 0.3 GB). With `freeing`
/// (the scene's own layers), a layer's depth is freed once its radii are
/// made, and its pixels once it is composited.
class FrameSpreads {
public:
    FrameSpreads(const LayeredScene& scene, const Camera& camera, const SpreadPlan& plan,
                 std::vector<Layer>* freeing, int nthreads);

    /// The layers' reports, with the pixels spread with the PSF image
    /// counted as each is set up.
    std::vector<LayerReport> reports;

    size_t size() const { return m_layers.size(); }

    /// Layer `i`'s spreads, set up now unless they were; false with `error`.
    bool set_up(size_t i, std::string& error);

    /// Every layer set up; false with `error`.
    bool set_up_all(std::string& error);

    /// The back-most layer with pixels, set up, or size(); false with `error`.
    bool set_up_back(size_t& back, std::string& error);

    /// Layer `i`'s spreads, once set up.
    LayerSpreads& operator[](size_t i) { return m_layers[i]; }

    /// Frees layer `i`'s spreads (and with `freeing` its pixels).
    void release(size_t i);

private:
    const LayeredScene& m_scene;
    std::vector<Layer>* m_freeing;
    const SpreadPlan& m_plan;
    const CircleOfConfusion m_coc;
    const std::vector<ChannelPass> m_passes;
    std::vector<LayerSpreads> m_layers;
    std::vector<bool> m_set;
    int m_nthreads;
};

}  // namespace defocus
