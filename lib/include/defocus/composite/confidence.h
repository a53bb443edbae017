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

/// One channel, "confidence": the share of `all`'s light (its luma) that
/// `part` holds, within [0, 1]; 0 where `all` has no light or `part` less
/// than a millionth of it. Both are composited RGBA over the same window.
bool light_fraction(OIIO::ImageBuf& dst, const OIIO::ImageBuf& all, const OIIO::ImageBuf& part,
                    const Imath::V3d& luma, int nthreads = 0);

}  // namespace defocus
