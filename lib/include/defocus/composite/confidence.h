// How much of a defocused image's light came from surfaces the input did
// not show: the confidence AOV.
#pragma once

#include <OpenImageIO/imagebuf.h>

#include <defocus/layers/layered_scene.h>

namespace defocus {

/// The rebuilt part of a layered scene: each layer with its colour where
/// Layer::rebuilt marks it and black elsewhere, its alpha and depth as
/// they are. Spread and composited like the scene, it gives the light of
/// the rebuilt surfaces in the image ("over" is linear in each layer's
/// colour, and the alphas are the scene's). False when no layer has a
/// rebuilt pixel: then that light is none.
bool rebuilt_part(const LayeredScene& scene, LayeredScene& part, int nthreads = 0);

/// rebuilt_part() with each rebuilt pixel's light (its luma) in the
/// channel of the estimate that made it: R patterns copied, G lines, B the
/// smooth fill; none for surfaces continued behind edges (the rest).
bool rebuilt_by_method(const LayeredScene& scene, LayeredScene& part, int nthreads = 0);

/// The confidence AOV's channels (aov_channel_names) of `all`: the share
/// of its light (its luma) that `part` holds, within [0, 1], 0 where `all`
/// has no light or `part` less than a millionth of it; then that share
/// split by method, from `by_method` (rebuilt_by_method spread and
/// composited), the surfaces continued behind edges taking the rest. All
/// three are composited RGBA over the same window.
bool light_fraction(OIIO::ImageBuf& dst, const OIIO::ImageBuf& all, const OIIO::ImageBuf& part,
                    const OIIO::ImageBuf& by_method, const Imath::V3d& luma,
                    int nthreads = 0);

}  // namespace defocus
