// Data channels carried through defocus by spreading quantities times alpha
// through the layers (see data_channels.h).
#include <defocus/composite/data_channels.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>

#include "composite/data_lookup.h"
#include "composite/data_spreads.h"
#include "composite/object_mattes.h"
#include "composite/sub_aperture.h"
#include "util/float_pixels.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// A data value safe to spread: NaN and infinity carry nothing (0), and
/// values beyond +-1e30 are clamped there, as sanitize() clamps colour
/// (float sums of them overflow).
float safe_value(float v)
{
    return std::isfinite(v) ? std::clamp(v, -1e30f, 1e30f) : 0.0f;
}

/// A depth safe to spread: the sky's infinity as the farthest value that
/// sums without overflow.
float safe_depth(float z)
{
    return std::min(z, 1e30f);
}

/// Where each quantity of a spread goes in the output.
struct QuantityTarget {
    int channel;           ///< dst channel
    DataKind kind;         ///< Average or Dominant
    int front = -1;        ///< for depth: the ZFront channel
    std::string source;    ///< the data channel read ("" = the layer's depth)
};

/// Composites one layer's spread quantities into dst (see data_channels.h).
void composite_quantities(ImageBuf& dst, Coverage& cov, const ImageBuf& spread, size_t layer,
                          const std::vector<QuantityTarget>& targets, bool first, int nthreads)
{
    const ROI lit = roi_intersection(spread.roi(), cov.roi);
    parallel_for(lit.ybegin, lit.yend, [&](int y) {
        const float* s = static_cast<const float*>(spread.pixeladdr(lit.xbegin, y));
        float* out = static_cast<float*>(dst.pixeladdr(lit.xbegin, y));
        for (int x = lit.xbegin; x < lit.xend;
             ++x, s += spread.nchannels(), out += dst.nchannels()) {
            const size_t i = cov.index(x, y);
            const float a = s[3];
            if (first)
                cov.alpha[i] = a + (1.0f - a) * cov.alpha[i];
            if (first && !cov.best_layer.empty()) {
                cov.best_weight[i] *= 1.0f - a;
                if (a > cov.best_weight[i] && a > reach_coverage) {
                    cov.best_weight[i] = a;
                    cov.best_layer[i] = int(layer);
                }
            }
            for (size_t j = 0; j < targets.size(); ++j) {
                const QuantityTarget& t = targets[j];
                if (t.kind == DataKind::Average)
                    out[t.channel] = s[j] + (1.0f - a) * out[t.channel];
                else if (cov.best_layer[i] == int(layer) && a > reach_coverage)
                    out[t.channel] = s[j] / a;
                if (t.front >= 0 && a > reach_coverage)
                    out[t.front] = s[j] / a;
            }
        }
    }, by_rows(nthreads));
}

/// The quantities of one spread, and whether each layer's own light
/// carries them (see Spreader::spread).
struct QuantityPass {
    std::vector<QuantityTarget> targets;
    bool own_light = false;
};

/// The spreads that carry `all`, per_spread at a time; the first also finds
/// what the layers cover. Through aperture cells (`cells`), the averages
/// and the coverage are composited per part of the lens as the colour is,
/// but a Dominant value, its layer's spread quantity over its spread alpha,
/// comes from the layer's own light: the cells' changes, kept in half,
/// round a quantity and its alpha apart, and the value would drift off
/// every layer's.
std::vector<QuantityPass> quantity_passes(const std::vector<QuantityTarget>& all, bool cells)
{
    std::vector<QuantityPass> passes;
    auto add = [&](const std::vector<QuantityTarget>& targets, bool own_light) {
        for (size_t first = 0; first < targets.size(); first += per_spread)
            passes.push_back({ { targets.begin() + first,
                                 targets.begin() + std::min(targets.size(), first + per_spread) },
                               own_light });
    };
    std::vector<QuantityTarget> averages, dominants;
    for (const QuantityTarget& t : all)
        (cells && t.kind == DataKind::Dominant ? dominants : averages).push_back(t);
    add(averages, false);
    add(dominants, true);
    if (passes.empty() || passes.front().own_light)
        passes.insert(passes.begin(), QuantityPass {});  // the coverage alone
    return passes;
}

/// Spreads the depth and the Average and Dominant channels in `passes`
/// through every layer; the first spread also fills `cov` (each layer's
/// alpha only when `keep_alphas`: mattes need it).
bool spread_quantities(ImageBuf& dst, Coverage& cov, Spreader& spreader,
                       const std::vector<DataLookup>& lookups,
                       const std::vector<QuantityPass>& passes, bool keep_alphas,
                       std::string& error)
{
    const LayeredScene& scene = spreader.scene;
    const std::vector<size_t> from = lit_layers(scene);
    for (const QuantityPass& pass : passes) {
        const std::vector<QuantityTarget>& targets = pass.targets;
        std::vector<Layer> layers;
        layers.reserve(from.size());  // see Spreader::spread
        for (size_t i : from) {
            const Layer& layer = scene.layers[i];
            const DataLookup& lookup = lookups[i];
            std::vector<int> channels;
            for (const QuantityTarget& t : targets)
                channels.push_back(t.source.empty() ? -1 : lookup.channel(t.source));
            const FloatPixels depth(layer.depth, layer.depth.roi());
            layers.push_back(quantity_layer(layer, layer.color.roi(),
                                            [&](int x, int y, float q[per_spread]) {
                for (size_t j = 0; j < channels.size(); ++j)
                    q[j] = targets[j].source.empty() ? safe_depth(*depth(x, y))
                           : channels[j] >= 0       ? safe_value(lookup(x, y)[channels[j]])
                                                    : 0.0f;
            }, spreader.nthreads));
        }
        const bool first_pass = &pass == &passes.front();
        if (!spreader.spread(std::move(layers), from, [&](size_t i, const ImageBuf& s) {
                composite_quantities(dst, cov, s, i, targets, first_pass, spreader.nthreads);
                const int alpha[] = { 3 };
                if (first_pass && keep_alphas)
                    ImageBufAlgo::channels(cov.layer_alpha[i], s, 1, alpha);
            }, error, pass.own_light))
            return false;
    }
    return true;
}

/// Divides the Average channels by the alpha they were composited with,
/// and makes each normal of three channels unit length again.
void finish_quantities(ImageBuf& dst, const Coverage& cov, const std::vector<int>& averages,
                       const std::vector<std::array<int, 3>>& normals, int nthreads)
{
    const ROI& roi = cov.roi;
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            float* out = static_cast<float*>(dst.pixeladdr(x, y));
            const float a = cov.alpha[cov.index(x, y)];
            for (int c : averages)
                out[c] = a > reach_coverage ? out[c] / a : 0.0f;
            for (const auto& n : normals) {
                const float length = std::sqrt(out[n[0]] * out[n[0]] + out[n[1]] * out[n[1]]
                                               + out[n[2]] * out[n[2]]);
                if (length > 0.0f)
                    for (int c : n)
                        out[c] /= length;
            }
        }
    }, by_rows(nthreads));
}

/// The dst channel of each quantity and set of `plan`, named as
/// DataPlan::output_channels() names them; the normals grouped by three
/// channels of one set.
void lay_out(const DataPlan& plan, const std::vector<std::string>& names,
             std::vector<QuantityTarget>& targets, std::vector<ObjectSet>& sets,
             std::vector<int>& averages, std::vector<std::array<int, 3>>& normals)
{
    auto channel = [&](const std::string& name) {
        return int(std::find(names.begin(), names.end(), name) - names.begin());
    };
    if (plan.depth) {
        targets.push_back({ channel("Z"), DataKind::Average, channel("ZFront"), "" });
        averages.push_back(channel("Z"));
    }
    std::map<std::string, std::vector<int>> normal_sets;
    for (const DataChannel& c : plan.channels) {
        if (c.kind == DataKind::Id) {
            sets.push_back({ false, { c.name }, { channel(c.name) } });
            continue;
        }
        targets.push_back({ channel(c.name), c.kind, -1, c.name });
        if (c.kind == DataKind::Average)
            averages.push_back(channel(c.name));
        if (c.normal)
            normal_sets[c.name.substr(0, c.name.rfind('.'))].push_back(channel(c.name));
    }
    for (const auto& [set, channels] : normal_sets)
        if (channels.size() == 3)
            normals.push_back({ channels[0], channels[1], channels[2] });
    for (const CryptoSet& crypto : plan.crypto) {
        ObjectSet set { true, crypto.channels, {} };
        for (const std::string& name : crypto.channels)
            set.outputs.push_back(channel(name));
        sets.push_back(std::move(set));
    }
}

}  // namespace

bool data_channels(ImageBuf& dst, const ImageBuf& result, const LayeredScene& scene,
                   const Camera& camera, const SpreadOptions& spread,
                   const ApertureImages& images, OutputWindow window, const DataPlan& plan,
                   int nthreads, const std::function<bool(int, int)>& keep_going)
{
    const ROI roi = result.roi();
    const std::vector<std::string> names = plan.output_channels();
    ImageSpec spec(roi.width(), roi.height(), int(names.size()), TypeFloat);
    spec.x = roi.xbegin;
    spec.y = roi.ybegin;
    spec.channelnames = names;
    dst.reset(spec, InitializePixels::Yes);
    const ReachOnly reach = reach_only(camera, spread, images);
    Spreader spreader { scene, reach, window, nthreads, keep_going };
    std::vector<DataLookup> lookups;
    for (const Layer& layer : scene.layers)
        lookups.emplace_back(layer);
    std::vector<QuantityTarget> targets;
    std::vector<ObjectSet> sets;
    std::vector<int> averages;
    std::vector<std::array<int, 3>> normals;
    lay_out(plan, names, targets, sets, averages, normals);
    // Which layer weighs most is asked only for the Dominant channels.
    const size_t pixels = size_t(roi.npixels());
    const size_t ranked = std::any_of(targets.begin(), targets.end(),
                                      [](const QuantityTarget& t) {
                                          return t.kind == DataKind::Dominant;
                                      })
                              ? pixels
                              : 0;
    Coverage cov { roi, std::vector<float>(pixels, 0.0f), std::vector<float>(ranked, 0.0f),
                   std::vector<int>(ranked, -1), std::vector<ImageBuf>(scene.layers.size()) };
    std::string error;
    std::vector<std::vector<ObjectExtent>> objects;
    const std::vector<QuantityPass> passes
        = quantity_passes(targets, takes_aperture_cells(spread, scene));
    spreader.total = int(passes.size());
    for (const ObjectSet& set : sets) {
        objects.push_back(find_objects(set, scene, lookups, nthreads));
        if (!plausible_ids(set, objects.back(), roi, error)) {
            dst.errorfmt("{}", error);
            return false;
        }
        spreader.total += object_spreads(objects.back());
    }
    if (!spread_quantities(dst, cov, spreader, lookups, passes, !sets.empty(), error)) {
        dst.errorfmt("{}", error);
        return false;
    }
    finish_quantities(dst, cov, averages, normals, nthreads);
    for (size_t s = 0; s < sets.size(); ++s) {
        TopShares top(pixels, sets[s].ranks());
        if (!spread_objects(sets[s], objects[s], spreader, lookups, cov, top, error)) {
            dst.errorfmt("{}", error);
            return false;
        }
        write_objects(dst, sets[s], top, cov, result, nthreads);
    }
    return true;
}

}  // namespace defocus
