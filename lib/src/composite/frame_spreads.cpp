#include "composite/frame_spreads.h"

#include <OpenImageIO/strutil.h>

#include <defocus/composite/defocus_layers.h>

namespace defocus {

using namespace OIIO;
using Strutil::fmt::format;

std::vector<ChannelPass> channel_passes(const Camera& camera)
{
    constexpr ChannelPass all_channels { CocChannel::Green, { true, true, true }, true };
    constexpr ChannelPass green_and_alpha { CocChannel::Green, { false, true, false }, true };
    const bool lateral = camera.lateral_ca != 0.0;
    if (camera.axial_ca == 0.0) {
        ChannelPass one = lateral ? green_and_alpha : all_channels;
        one.magnified = lateral;
        return { one };
    }
    const ChannelPass red_and_blue { CocChannel::RedBlue,
                                     { !lateral, false, !lateral }, false, lateral };
    return { green_and_alpha, red_and_blue };
}

const LayerPass* storable_pass(const LayerSpreads& layer)
{
    return layer.passes.size() == 1 && layer.passes[0].spread.rows
                   && !layer.passes[0].channels.magnified
               ? &layer.passes[0]
               : nullptr;
}

FrameSpreads::FrameSpreads(const LayeredScene& scene, const Camera& camera,
                           const SpreadPlan& plan, std::vector<Layer>* freeing, int nthreads)
    : reports(scene.reports)
    , m_scene(scene)
    , m_freeing(freeing)
    , m_plan(plan)
    , m_coc(camera, scene.spec.roi_full())
    , m_passes(channel_passes(camera))
    , m_layers(scene.layers.size())
    , m_set(scene.layers.size(), false)
    , m_nthreads(nthreads)
{
}

bool FrameSpreads::set_up(size_t i, std::string& error)
{
    if (m_set[i])
        return true;
    m_set[i] = true;
    if (reports[i].pixels == 0)
        return true;
    const Layer& layer = m_scene.layers[i];
    LayerSpreads& l = m_layers[i];
    if (m_plan.in_engine)
        l.color_pixels = FloatPixels(layer.color, layer.color.roi());
    for (const ChannelPass& channels : m_passes) {
        LayerPass& p = l.passes.emplace_back();
        p.channels = channels;
        ImageBuf radius;
        if (!coc_radius(radius, layer.depth, m_coc, {}, m_nthreads, channels.coc)) {
            error = format("layer '{}': {}", layer.name, radius.geterror());
            return false;
        }
        if (m_freeing && &channels == &m_passes.back())
            (*m_freeing)[i].depth.reset();
        if (!spread_pass(m_plan, layer, l.color_pixels, reports[i], std::move(radius), p.spread,
                         error, m_nthreads)) {
            error = format("layer '{}': {}", layer.name, error);
            return false;
        }
        if (channels.alpha && !m_plan.in_engine)
            reports[i].psf_pixels = p.spread.psf_pixels;
    }
    return true;
}

bool FrameSpreads::set_up_all(std::string& error)
{
    for (size_t i = 0; i < size(); ++i)
        if (!set_up(i, error))
            return false;
    return true;
}

bool FrameSpreads::set_up_back(size_t& back, std::string& error)
{
    for (back = 0; back < size() && reports[back].pixels == 0; ++back) {}
    return back == size() || set_up(back, error);
}

void FrameSpreads::release(size_t i)
{
    m_layers[i] = LayerSpreads();
    if (m_freeing) {
        Layer& layer = (*m_freeing)[i];
        layer.color.reset();
        layer.rebuilt.reset();
        layer.data.reset();
    }
}

}  // namespace defocus
