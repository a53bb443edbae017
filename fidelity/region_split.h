// A render's error against a path-traced truth, split into what the
// pinhole view could know and what only the lens reveals (the method of
// ../shared/tools/known_region.py, for the tests and the benchmark).
//
// A layered scene holds surfaces the pinhole view cannot see, behind
// nearer ones; the lens sees around the near ones' edges, so part of a
// defocused image receives light from them. A flat or deep render lacks
// them and must rebuild them. Removing them from the layers ("culling")
// and defocusing both gives the revealed region: where the two differ.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

namespace defocus_fidelity {

/// Writes `out`, the layered EXR `in` (a part a layer: R, G, B, A, Z)
/// without the pixels the pinhole view cannot see: those covered by the
/// nearer layers at that pixel (by Z) to `covered` or more. They become
/// clear, at depth 1e10. False with `error`.
bool cull_hidden(const std::string& in, const std::string& out, std::string& error,
                 double covered = 0.999);

/// An image as the garden metric takes it: R, G, B over the display window
/// of `image` (or of `window_of`, where given), clamped to [0, 1] and
/// sRGB-encoded, row by row.
std::vector<float> display_srgb(const OIIO::ImageBuf& image,
                                const OIIO::ImageBuf* window_of = nullptr);

/// Per pixel of the display window, whether the light of the full layers'
/// render `full` and the culled layers' `culled` differ by more than 0.01
/// in any sRGB channel.
std::vector<bool> revealed_pixels(const std::vector<float>& full, const std::vector<float>& culled);

/// PSNR in dB (peak 1) of a render against the truth, over the known
/// region, the revealed region and all of it.
struct RegionPsnr {
    double known, revealed, all;
    double revealed_share;  ///< of the pixels
};
RegionPsnr region_psnr(const std::vector<float>& image, const std::vector<float>& truth,
                       const std::vector<bool>& revealed);

/// Each input of a scene laid out as garden's (`layers.exr`, `flat.exr`,
/// `deep.exr` in `scene`) against the truth `truth`, split by region.
struct SceneSplit {
    RegionPsnr layers, flat, deep;
};

/// Defocuses an input into an output file: false where it failed.
using Render = std::function<bool(const std::string& input, const std::string& output)>;

/// The split of the scene's layers, flat and deep renders as `render`
/// makes them: the revealed region from the layers and the layers with the
/// hidden pixels culled. Files go to `work`. False with `error`.
bool split_scene(const std::string& scene, const std::string& truth, const std::string& work,
                 const Render& render, SceneSplit& split, std::string& error);

}  // namespace defocus_fidelity
