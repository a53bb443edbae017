// Internal: the objects of ID channels and cryptomatte sets, carried
// through defocus as each object's share of the spread alpha (see
// data_channels.h).
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "composite/data_lookup.h"
#include "composite/data_spreads.h"

namespace defocus {

/// An ID channel or a cryptomatte set: what each pixel's data says of the
/// objects it shows.
struct ObjectSet {
    bool crypto = false;
    std::vector<std::string> channels;  ///< ID: one; crypto: id, coverage, id, ...
    std::vector<int> outputs;           ///< dst channels, the same layout
    int ranks() const { return crypto ? int(outputs.size()) / 2 : 1; }
};

/// The most objects read from one pixel.
constexpr int max_ranks = 16;

struct PixelObject {
    uint32_t id;
    float fraction;  ///< of the pixel's alpha
};

/// Where an object lies in one layer, and whether it is all of that
/// layer's light: every pixel with alpha wholly the object's. There its
/// matte is the layer's alpha, and so is the matte's spread.
struct Presence {
    OIIO::ROI roi;
    int64_t whole_pixels = 0;  ///< pixels wholly the object's
    bool all_of_layer = false;

    /// Takes in `pixels`, `whole` of them wholly the object's.
    void add(const OIIO::ROI& pixels, int64_t whole)
    {
        roi = OIIO::roi_union(roi, pixels);
        whole_pixels += whole;
    }
};

/// An object and, per layer, where it lies.
struct ObjectExtent {
    uint32_t id;
    std::map<size_t, Presence> layers;
    OIIO::ROI all;

    /// Whether its matte is spread in some layer: it is not all of that
    /// layer's light.
    bool spreads() const
    {
        return std::any_of(layers.begin(), layers.end(),
                           [](const auto& layer) { return !layer.second.all_of_layer; });
    }
};

/// Per output pixel, the objects with the largest shares of its alpha,
/// largest first.
class TopShares {
public:
    TopShares(size_t pixels, int ranks)
        : m_ranks(ranks)
        , m_shares(pixels * ranks, PixelObject { 0, 0.0f })
    {
    }

    void insert(size_t pixel, uint32_t id, float share)
    {
        PixelObject* top = &m_shares[pixel * m_ranks];
        if (!(share > top[m_ranks - 1].fraction))
            return;
        int k = m_ranks - 1;
        for (; k > 0 && top[k - 1].fraction < share; --k)
            top[k] = top[k - 1];
        top[k] = { id, share };
    }

    const PixelObject* operator[](size_t pixel) const { return &m_shares[pixel * m_ranks]; }

private:
    int m_ranks;
    std::vector<PixelObject> m_shares;
};

/// Whether `objects` of an ID channel are objects: a continuous channel
/// declared an ID (a user's mistake) has a value per pixel, each strewn
/// over the frame. Past 64 spreads of the frame (9,938 compact IDs take
/// under one, 5,828 values of a colour channel 2,000), false with `error`.
bool plausible_ids(const ObjectSet& set, const std::vector<ObjectExtent>& objects,
                   const OIIO::ROI& frame, std::string& error);

/// Every object of `set` the scene's layers show, ordered by place so that
/// objects spread together lie close, those spread at all first.
std::vector<ObjectExtent> find_objects(const ObjectSet& set, const LayeredScene& scene,
                                       const std::vector<DataLookup>& lookups, int nthreads);

/// The spreads spread_objects() makes of `objects`: one for each three of
/// them of which one is not all of the light of some layer it lies in.
int object_spreads(const std::vector<ObjectExtent>& objects);

/// Spreads the mattes of `objects`, three at a time, each cropped to where
/// it lies in each layer, and keeps each pixel's largest shares: a matte's
/// spread in one layer, attenuated by the layers in front, summed. Where
/// the three are each all of a layer's light, their mattes there are that
/// layer's spread alpha, kept in `cov`: nothing is spread.
bool spread_objects(const ObjectSet& set, const std::vector<ObjectExtent>& objects,
                    Spreader& spreader, const std::vector<DataLookup>& lookups,
                    const Coverage& cov, TopShares& top, std::string& error);

/// Writes a set's largest shares into dst: cryptomatte as rank pairs,
/// scaled from the data spread's alpha to the result's; an ID as the ID
/// of the largest share (0 where nothing is).
void write_objects(OIIO::ImageBuf& dst, const ObjectSet& set, const TopShares& top,
                   const Coverage& cov, const OIIO::ImageBuf& result, int nthreads);

}  // namespace defocus
