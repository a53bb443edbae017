// Internal: how a frame's layers are spread, decided once per frame, and
// each layer's spread set up as the plan says. Compositing then takes the
// spreads as they come (composite/defocus_layers.cpp).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebuf.h>

#include <defocus/layers/layered_scene.h>
#include <defocus/optics/camera.h>
#include <defocus/shot/options.h>
#include <defocus/spread/aperture_images.h>
#include <defocus/spread/cateye.h>

#include "spread/spread_engine.h"
#include "util/float_pixels.h"

namespace defocus {

/// What every layer of a frame shares in its spread.
struct SpreadPlan {
    const SpreadOptions* options = nullptr;
    const ApertureImages* images = nullptr;
    Imath::V3d luma;  ///< weights by which highlights are found
    /// A shape aperture's profile, and its footprints sized to the
    /// frame's largest blur; null for the box, tent and smooth.
    std::shared_ptr<const RowProfile> profile;
    std::unique_ptr<ShapePrograms> programs;
    SpreadMethod method = SpreadMethod::Box;
    /// The aperture's squeeze, the pixel aspect's included
    /// (effective_aperture): the box's rectangles take it.
    double aspect = 1.0;
    CatEye cateye;
    /// Layers go through the engine, composited as they are spread; else
    /// through tent's or smooth's own passes (`smooth_order`), composited
    /// as they are spread too; else each is spread apart, as an image (the
    /// hybrid method, a cat's eye with the box, exact spreading, tent or
    /// smooth).
    bool in_engine = false;
    /// Tent (2) or smooth (3) handed on a row at a time (SmoothRows); 0
    /// otherwise.
    int smooth_order = 0;
};

/// The plan for a frame whose layers' reports are `reports`, through
/// `camera`, with display window `display`. False with `error` when a mask
/// aperture comes without its shape. `options` and `images` must outlive
/// the plan.
bool plan_spread(const SpreadOptions& options, const ApertureImages& images,
                 const Camera& camera, const OIIO::ROI& display,
                 const std::vector<LayerReport>& reports, const Imath::V3d& luma,
                 SpreadPlan& plan, std::string& error);

/// One spread of a layer: set up to be handed on a row at a time (by the
/// engine, with the radii, float radii and highlights it reads while it
/// lives, or by tent's and smooth's passes, with the radii), or done apart
/// into `apart`.
struct PassSpread {
    OIIO::ImageBuf radius;
    FloatPixels radius_pixels;
    std::vector<uint8_t> highlights;
    std::unique_ptr<RowSpread> rows;  ///< the engine's, or tent's and smooth's
    OIIO::ImageBuf apart;
    int64_t psf_pixels = 0;  ///< pixels spread with the PSF image (hybrid)

    /// Every pixel the spread can light.
    OIIO::ROI extent() const { return rows ? rows->extent() : apart.roi(); }
};

/// Spreads `layer` (described by `report`) with CoC radii `radius` as
/// `plan` says, into `out`. With the engine, `color` holds the layer's
/// float colour, and must outlive `out`; so must the layer, for tent and
/// smooth. False with `error`.
bool spread_pass(const SpreadPlan& plan, const Layer& layer, const FloatPixels& color,
                 const LayerReport& report, OIIO::ImageBuf&& radius, PassSpread& out,
                 std::string& error, int nthreads);

}  // namespace defocus
