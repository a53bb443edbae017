// A scene as read from files: layers given as such, flat renders and deep
// images. Flat and deep content is cut into depth layers by layering.h.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

namespace defocus {

/// How a pixel that a render did not show was rebuilt (Layer::rebuilt):
/// by the estimate that weighs most in it.
enum class RebuiltBy : uint8_t {
    Seen = 0,   ///< not rebuilt
    Smooth,     ///< the push-pull average
    Lines,      ///< structure continued along lines across a thin hole
    Patterns,   ///< a pattern copied from one period along
    Continued,  ///< a surface continued behind a nearer edge (mixed pixels, cut lights)
};

/// One layer: premultiplied colour and its planar camera-space depth over
/// the same data window. A layer need not be planar.
struct Layer {
    std::string name;
    OIIO::ImageBuf color;  ///< float R,G,B,A, alpha_channel = 3
    OIIO::ImageBuf depth;  ///< float Z
    /// Where the colour is rebuilt, not seen: the background a flat render
    /// or a deep image hides behind nearer layers, filled in by slicing.
    /// One uint8 channel, nonzero there (the RebuiltBy of each pixel),
    /// over part of the layer's window; empty when nothing is.
    OIIO::ImageBuf rebuilt {};
    /// The data channels (IDs, cryptomatte, P, N: see
    /// composite/data_channels.h) of the render or part the layer was cut
    /// from, float, over that source's data window: a layer pixel's data is
    /// the source pixel's at the same place. Shared by every layer cut from
    /// one source; null when none were asked for.
    std::shared_ptr<const OIIO::ImageBuf> data {};
};

/// One deep sample: premultiplied colour, alpha, and the depth interval it
/// covers (zback == z for a point sample).
struct DeepSample {
    float r, g, b, a;
    float z, zback;
};

/// A deep image: every pixel's samples, in file order.
struct DeepImage {
    std::string name;
    OIIO::ROI roi;                  ///< data window
    std::vector<uint64_t> offsets;  ///< pixel i's samples are [offsets[i], offsets[i+1])
    std::vector<DeepSample> samples;
    /// Data channels read beside colour and depth (see Layer::data), and
    /// their values: data_names.size() of them per sample, in sample order.
    std::vector<std::string> data_names;
    std::vector<float> data;

    int64_t pixel_index(int x, int y) const
    {
        return int64_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin);
    }
};

struct Scene {
    std::string source;  ///< the file(s) it came from, for messages
    /// Display window, pixel type and metadata of the (first) input, kept
    /// for the output. Its data window is the union of the inputs'.
    OIIO::ImageSpec spec;
    std::vector<Layer> layers;   ///< layers as given: spread as they are
    std::vector<Layer> flat;     ///< flat renders (RGBA+Z), to be sliced
    std::vector<DeepImage> deep; ///< deep images, to be sliced
    /// How reading took what the files did not say, for -v, e.g. "x.exr:
    /// no alpha channel, taken as opaque".
    std::vector<std::string> notes;
};

/// Calls on_layer(layer) for every layer and flat render of `scene`, then
/// on_deep(image) for every deep image, until one returns false (false
/// then): the one walk over every piece of content. `scene` may be const.
template<typename SceneType, typename OnLayer, typename OnDeep>
bool for_each_content(SceneType& scene, OnLayer&& on_layer, OnDeep&& on_deep)
{
    for (auto* list : { &scene.layers, &scene.flat })
        for (auto& layer : *list)
            if (!on_layer(layer))
                return false;
    for (auto& image : scene.deep)
        if (!on_deep(image))
            return false;
    return true;
}

/// Removes the attributes that describe one part of an input file (its
/// name, view, part count), not a result made from all of them.
void erase_part_attributes(OIIO::ImageSpec& spec);

/// What sanitize() changed, so that -v can say it.
struct PixelCounts {
    int64_t nonfinite_color = 0;    ///< NaN or inf in R,G,B or A: dropped
    int64_t huge_color = 0;         ///< R, G or B beyond +-1e30: clamped there
    int64_t alpha_above_one = 0;    ///< A above 1: clamped to 1
    int64_t bad_depth       = 0;    ///< Z NaN, zero or negative: moved to infinity
    int64_t transparent_light = 0;  ///< alpha <= 0 with colour: dropped
    int64_t edge_depth = 0;  ///< partly covered, no depth: given its covered neighbours'
};

/// Makes every pixel and deep sample safe to spread, and counts what it
/// changed:
///  - a pixel with NaN or inf colour or alpha is dropped (made transparent);
///  - colour beyond +-1e30 is clamped there (float sums of it overflow);
///  - alpha above 1 is clamped to 1 ("over" would amplify what is behind);
///  - a pixel with alpha <= 0 carries no light: it is cleared whatever its
///    colour and depth (renders write Z = 0 or 1e10 there);
///  - a covered pixel with depth NaN, -inf, zero or negative is taken as
///    infinitely far (+inf is a valid depth: the sky);
///  - a partly covered pixel of a layer or flat render (an antialiased
///    edge) whose depth is invalid or the renderer's "nothing" (infinite,
///    or 1e9 and beyond: renderers write 1e10) takes the depth of its most
///    covered neighbour of the 8 that has a depth; otherwise it would be
///    blurred as infinitely far, a halo around the object.
/// Deep samples follow the same rules; a ZBack that is not a valid depth
/// at or behind Z is set to Z.
PixelCounts sanitize(Scene& scene, int nthreads = 0);

}  // namespace defocus
