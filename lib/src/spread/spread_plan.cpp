#include "spread/spread_plan.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>

#include <defocus/spread/spread.h>

#include "spread/pixels_alone.h"
#include "spread/smooth_rows.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;

namespace {

/// A layer spread on its own, as an image: the hybrid method (highlights
/// with the PSF image, the rest with the aperture's filter), the smooth
/// filters, or exact spreading and the box clipped by a cat's eye. The box
/// takes the aperture's squeeze `aspect`.
bool spread_apart(ImageBuf& dst, const ImageBuf& color, const ImageBuf& radius,
                  const SpreadOptions& spread, const ApertureImages& images,
                  const RowProfile* profile, double aspect, const CatEye& cateye,
                  const Imath::V3d& luma, int64_t& psf_pixels, int nthreads)
{
    const bool clipped = cateye.amount > 0.0;
    auto fast = [&](ImageBuf& out, const ImageBuf& in) {
        if (clipped) {
            switch (spread.aperture.shape) {
            case ApertureShape::Box:
                return spread_cateye(out, in, radius, BoxProfile(aspect), cateye, {}, nthreads);
            case ApertureShape::Tent:
            case ApertureShape::Smooth: {
                const int order = spread.aperture.shape == ApertureShape::Tent ? 2 : 3;
                const Psf psf = [order](double r) { return smooth_footprint(order, r); };
                return spread_cateye(out, in, radius, psf, cateye, {}, nthreads);
            }
            default:
                return spread.exact_shape
                           ? spread_cateye(out, in, radius, *profile, cateye, {}, nthreads)
                           : spread_cateye_bounded(out, in, radius, *profile, cateye,
                                                   { exact_highlight_threshold, luma }, {},
                                                   nthreads);
            }
        }
        switch (spread.aperture.shape) {
        case ApertureShape::Box: return spread_box(out, in, radius, aspect, {}, nthreads);
        case ApertureShape::Tent: return spread_smooth(out, in, radius, 2, {}, nthreads);
        case ApertureShape::Smooth: return spread_smooth(out, in, radius, 3, {}, nthreads);
        default:
            return spread.exact_shape
                       ? spread_scanline(out, in, radius, *profile, {}, nthreads)
                       : spread_aperture(out, in, radius, *profile,
                                         { exact_highlight_threshold, luma }, {}, nthreads);
        }
    };
    if (!images.psf)
        return fast(dst, color);

    const std::vector<uint8_t> slow = visible_bokeh(color, radius,
                                                    { spread.hybrid_threshold, luma }, nthreads);
    psf_pixels = std::count(slow.begin(), slow.end(), uint8_t(1));
    // Split the layer: the selected pixels go one way, the rest the other.
    ImageBuf fast_part(color.spec()), slow_part(color.spec());
    const ROI roi = color.roi();
    parallel_for(roi.ybegin, roi.yend, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const bool is_slow = slow[size_t(y - roi.ybegin) * roi.width() + (x - roi.xbegin)];
            const float* c = static_cast<const float*>(color.pixeladdr(x, y));
            float* f = static_cast<float*>(fast_part.pixeladdr(x, y));
            float* s = static_cast<float*>(slow_part.pixeladdr(x, y));
            for (int k = 0; k < 4; ++k) {
                f[k] = is_slow ? 0.0f : c[k];
                s[k] = is_slow ? c[k] : 0.0f;
            }
        }
    }, by_rows(nthreads));
    const std::shared_ptr<const PsfImage> image = images.psf;
    const Psf psf = [image](double r) { return image->footprint(r); };
    ImageBuf fast_spread, slow_spread;
    if (!fast(fast_spread, fast_part)
        || !(clipped ? spread_cateye(slow_spread, slow_part, radius, psf, cateye, {}, nthreads)
                     : spread_direct(slow_spread, slow_part, radius, psf, {}, nthreads))) {
        dst.errorfmt("{}{}", fast_spread.geterror(), slow_spread.geterror());
        return false;
    }
    return ImageBufAlgo::add(dst, fast_spread, slow_spread, {}, nthreads);
}

}  // namespace

bool plan_spread(const SpreadOptions& options, const ApertureImages& images,
                 const Camera& camera, const ROI& display,
                 const std::vector<LayerReport>& reports, const Imath::V3d& luma,
                 SpreadPlan& plan, std::string& error)
{
    plan.options = &options;
    plan.images = &images;
    plan.luma = luma;
    // Shape apertures share one profile and its footprints, sized to the
    // largest blur.
    double max_radius = 0.0;
    for (const LayerReport& d : reports)
        max_radius = std::max({ max_radius, 0.5 * std::abs(d.coc_min), 0.5 * std::abs(d.coc_max) });
    const Aperture aperture = effective_aperture(options.aperture, camera.pixel_aspect);
    plan.aspect = aperture.aspect;
    if (aperture.shape == ApertureShape::Disc || aperture.shape == ApertureShape::Polygon) {
        plan.profile = std::make_shared<ApertureProfile>(aperture);
    } else if (aperture.shape == ApertureShape::Mask) {
        if (!images.mask) {
            error = "a mask aperture needs its shape (read_aperture_mask)";
            return false;
        }
        plan.profile = camera.pixel_aspect == 1.0 ? images.mask
                                                  : images.mask->squeezed(1.0 / camera.pixel_aspect);
    }
    plan.method = aperture.shape == ApertureShape::Box ? SpreadMethod::Box
                  : options.exact_shape                ? SpreadMethod::Exact
                                                       : SpreadMethod::Bounded;
    const Imath::V2d centre = optical_centre(camera, display);
    plan.cateye.amount = camera.cateye;
    plan.cateye.centre = centre;
    const double aspect = camera.pixel_aspect;
    for (const int x : { display.xbegin, display.xend })
        for (const int y : { display.ybegin, display.yend })
            plan.cateye.corner_distance
                = std::max(plan.cateye.corner_distance,
                           Imath::V2d((x - centre.x) * aspect, y - centre.y).length()
                               / std::sqrt(aspect));
    plan.cateye.clip_aspect = 1.0 / aspect;
    // A cat's eye goes through the engine with merged blocks only: exact
    // spreading and the box take it pixel by pixel.
    const bool clipped = plan.cateye.amount != 0.0;
    plan.in_engine = !images.psf && aperture.shape != ApertureShape::Tent
                     && aperture.shape != ApertureShape::Smooth
                     && (!clipped || plan.method == SpreadMethod::Bounded);
    plan.smooth_order = images.psf || clipped                 ? 0
                        : aperture.shape == ApertureShape::Tent   ? 2
                        : aperture.shape == ApertureShape::Smooth ? 3
                                                                  : 0;
    if (plan.profile)
        plan.programs = std::make_unique<ShapePrograms>(
            plan.profile, max_radius, plan.in_engine ? plan.cateye : CatEye {});
    return true;
}

bool spread_pass(const SpreadPlan& plan, const Layer& layer, const FloatPixels& color,
                 const LayerReport& report, ImageBuf&& radius, PassSpread& out,
                 std::string& error, int nthreads)
{
    out.radius = std::move(radius);
    const CatEye cateye = plan.cateye.of_layer(report.coc_min, report.coc_max);
    if (plan.smooth_order) {
        out.rows = SmoothRows::make(layer.color, out.radius, plan.smooth_order, {}, error,
                                    nthreads);
        return out.rows != nullptr;
    }
    if (!plan.in_engine) {
        if (!spread_apart(out.apart, layer.color, out.radius, *plan.options, *plan.images,
                          plan.profile.get(), plan.aspect, cateye, plan.luma, out.psf_pixels,
                          nthreads)) {
            error = out.apart.geterror();
            return false;
        }
        out.radius.reset();
        return true;
    }
    const ROI roi = layer.color.roi();
    out.radius_pixels = FloatPixels(out.radius, roi);
    SpreadSource source;
    source.roi = roi;
    source.color = color(roi.xbegin, roi.ybegin);
    source.radius = out.radius_pixels(roi.xbegin, roi.ybegin);
    source.box_aspect = plan.aspect;
    source.cateye_side = cateye.side;
    const double layer_radius = 0.5 * std::max(std::abs(report.coc_min), std::abs(report.coc_max));
    if (plan.method == SpreadMethod::Bounded && layer_radius >= smallest_merged_radius()) {
        out.highlights = visible_bokeh(layer.color, out.radius,
                                       { exact_highlight_threshold, plan.luma }, nthreads);
        add_pixels_alone(source, out.highlights, nthreads);
        source.keep_exact = out.highlights.data();
    }
    out.rows = std::make_unique<SpreadEngine>(source, plan.method, plan.programs.get(), nthreads);
    return true;
}

}  // namespace defocus
