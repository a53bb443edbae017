// Cutting flat renders and deep images into depth layers, so that the
// layered framework (spread each layer, composite back to front) applies.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <defocus/layers/layered_scene.h>
#include <defocus/scene.h>
#include <defocus/optics/camera.h>
#include <defocus/shot/options.h>

namespace defocus {

/// Layer boundaries in signed CoC, that is in 1/z: layer k holds the
/// content between boundary(k) and boundary(k + 1), nearest first.
class LayerBounds {
public:
    /// One layer spanning [coc_near, coc_far].
    LayerBounds(double coc_near = 0.0, double coc_far = 0.0);
    /// Layers between the given ascending boundaries (first and last are
    /// the nearest and farthest content).
    LayerBounds(std::vector<double> boundaries, double soft_band);

    int count() const { return int(m_bounds.size()) - 1; }
    double boundary(int i) const { return m_bounds[i]; }
    /// How wide, in CoC, the band about each boundary is whose content
    /// belongs to both layers (see share()).
    double soft_band() const { return m_band; }

    /// The layers a point with signed CoC `c` belongs to: `front` with
    /// weight `front_weight`, and front + 1 with the rest. Content within
    /// half the soft band of a boundary belongs to both, in proportion to
    /// its distance, so a surface that crosses a boundary shows no seam.
    struct Share {
        int front;
        float front_weight;
    };
    Share share(double c) const;

private:
    std::vector<double> m_bounds;
    double m_band = 0.0;
};

/// The layer bounds for a scene's flat and deep content under a camera.
/// With options.layers = N: N layers spaced uniformly in CoC. Otherwise
/// the bounds follow the occlusions: the two sides of every visible depth
/// discontinuity (a nearer surface beside or in front of one whose blur
/// differs visibly) go to different layers, with the fewest bounds, each
/// at the emptiest CoC (least alpha-weighted content) its sides allow; and
/// where a layer would still span more than max_coc_span, more bounds go
/// to the emptiest CoC within reach. So bounds fall in the gaps between
/// objects and rarely cut a surface.
LayerBounds choose_layer_bounds(const Scene& scene, const CircleOfConfusion& coc,
                                const LayeringOptions& options, int nthreads = 0);

/// The weights that split premultiplied colour and alpha `a` between two
/// adjacent layers so that the front part composited over the back part
/// gives back the original exactly: front w, back (1 - w) / (1 - w·a).
struct SplitWeights {
    float front, back;
};
SplitWeights split_weights(float front_weight, float a);

/// The layer pixels the hidden-background fill rebuilt, each counted by
/// the estimate that weighs most in it (see fill_hidden_background).
struct RebuiltPixels {
    int64_t smooth = 0;     ///< the push-pull average
    int64_t lines = 0;      ///< structure continued along lines across a thin hole
    int64_t patterns = 0;   ///< a pattern copied from one period along
    int64_t continued = 0;  ///< a surface continued behind a nearer edge (mixed pixels, cut lights)

    int64_t total() const { return smooth + lines + patterns + continued; }
    /// One more pixel rebuilt by `by` (not RebuiltBy::Seen).
    void add(RebuiltBy by)
    {
        ++(by == RebuiltBy::Smooth     ? smooth
           : by == RebuiltBy::Lines    ? lines
           : by == RebuiltBy::Patterns ? patterns
                                       : continued);
    }
    void add(const RebuiltPixels& other)
    {
        smooth += other.smooth;
        lines += other.lines;
        patterns += other.patterns;
        continued += other.continued;
    }
};

/// What cutting a scene into layers did, for -v.
struct Slicing {
    LayerBounds bounds;        ///< the layer bounds used
    int64_t mixed_pixels = 0;  ///< flat pixels split into two surfaces
    RebuiltPixels rebuilt;     ///< what the layers' hidden backgrounds hold
};

/// Cuts `scene`, sanitized (sanitize(): finite colour, depths positive or
/// +inf), into depth layers: its layers as they are, and its flat
/// renders and deep images cut at the bounds, cropped to their content,
/// all described and ordered back to front (order_layers) into `layered`.
/// Deep pixels follow OpenEXR's "Interpreting OpenEXR Deep Pixels":
/// samples sorted by Z then ZBack, volume samples spread over the depth
/// they span as the thin samples they are the limit of (the alpha-split
/// formula), and each layer's share of a pixel composited front to back
/// with an alpha-weighted Z. A flat render's
/// hidden background, the part of a layer behind nearer layers that one
/// render cannot see, is filled from the layer's visible surroundings (see
/// fill_hidden_background). A flat render's mixed pixels, on the silhouette
/// of a nearer surface, are cut as two fragments (find_mixed_pixels). Sets
/// `slicing` to what was done. False with `error` when the layers would
/// take more than options.memory_limit. `keep_going`, where given, is
/// asked before each layer is cut; false stops with the error "cancelled".
bool decompose_layers(Scene&& scene, const CircleOfConfusion& coc,
                      const LayeringOptions& options, LayeredScene& layered,
                      Slicing& slicing, std::string& error, int nthreads = 0,
                      const std::function<bool()>& keep_going = {});

/// The pixels of a layer that nearer layers hide and it does not cover,
/// and what the layer shows elsewhere, as cutting it finds them.
struct HiddenPixels {
    enum Flag : uint8_t {
        seen = 0,
        hidden = 1,     ///< nearer layers cover the pixel, and this one has nothing
        continued = 2,  ///< what this layer has is a surface continued behind a
                        ///< nearer one's edge (MixedPixel::far_continued)
    };
    std::vector<uint8_t> flags;  ///< per pixel of the layer's window, row by row
    OIIO::ROI continued_box;     ///< bounds the `continued` pixels; empty when none
    /// Mean brightness ((R + G + B) / 3, at least 0) per unit of alpha of
    /// the covered pixels not hidden (1 where there are none): the fill
    /// weighs brighter pixels down to it, so that a small light beside a
    /// hole does not flood it.
    float seen_brightness = 1.0f;
};

/// Hidden-surface filling: the pixels of `layer` flagged `hidden` in `holes`
/// (hidden behind nearer layers) are rebuilt from the layer's observed pixels around
/// them, covered or empty. Where a straight line crosses the hole within
/// 4 * max_distance pixels between two ends that agree, and along which the
/// surface runs outside the hole, the structure is continued along it
/// (stripes, edges, checkers behind a thin occluder); elsewhere, and blended
/// in as the ends disagree, pixels take the push-pull average (Gortler et al.
/// 1996) found on the coarsest pyramid level needed, up to `max_distance`
/// pixels away. Premultiplied colour and alpha are filled, and the
/// alpha-weighted depth. A run of hidden pixels up to 32 px along a row or
/// column is also copied from the same line where the pixels beside it
/// repeat (a checker or bricks behind a pole). The pixels filled, and
/// those flagged `continued`, are marked in layer.rebuilt, and counted.
RebuiltPixels fill_hidden_background(Layer& layer, const HiddenPixels& holes,
                                     double max_distance, int nthreads = 0);

/// The window over which fill_hidden_background(layer, holes,
/// max_distance) gives the same result as over all of `frame`, for a layer
/// whose content lies within `content`: the content grown by the fill's
/// reach, on the grid of its coarsest pyramid level, within `frame`.
OIIO::ROI hidden_background_window(const OIIO::ROI& content, const OIIO::ROI& frame,
                                   double max_distance);

}  // namespace defocus
