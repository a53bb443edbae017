#include "io/part_layer.h"

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include "util/fresh_image.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;
using Strutil::fmt::format;

namespace {

/// A layer over `window` of a part whose header is `from` (display
/// window), its pixels not yet set; false with `error` when it would not
/// fit in memory.
bool allocate_layer(const std::string& name, const ROI& window, const ImageSpec& from,
                    Layer& layer, const std::string& filename, std::string& error)
{
    if (window.npixels() <= 0) {
        error = format("{}: an empty data window", filename);
        return false;
    }
    auto layer_spec = [&](int nchannels) {
        ImageSpec spec(window, TypeFloat);
        spec.nchannels   = nchannels;
        spec.full_x      = from.full_x;
        spec.full_y      = from.full_y;
        spec.full_width  = from.full_width;
        spec.full_height = from.full_height;
        return spec;
    };
    ImageSpec color_spec = layer_spec(4), depth_spec = layer_spec(1);
    color_spec.channelnames  = { "R", "G", "B", "A" };
    color_spec.alpha_channel = 3;
    depth_spec.channelnames  = { "Z" };
    depth_spec.z_channel     = 0;
    layer.name = name;
    reset_for_overwrite(layer.color, color_spec, 0);
    reset_for_overwrite(layer.depth, depth_spec, 0);
    return true;
}

/// Sets a layer's colour from channels `color` of `part` and, when
/// `depth` is not -1, its depth from that channel of the same part. Colour
/// without alpha (color[3] = -1) is left for set_opaque().
void copy_layer(Layer& layer, const ImageBuf& part, const int color[4], int depth)
{
    const ROI window = part.roi();
    const int n      = part.nchannels();
    const int ncolor = color[3] >= 0 ? 4 : 3;
    parallel_for(window.ybegin, window.yend, [&](int y) {
        float* rgba = static_cast<float*>(layer.color.pixeladdr(window.xbegin, y));
        float* z    = static_cast<float*>(layer.depth.pixeladdr(window.xbegin, y));
        const float* src = static_cast<const float*>(part.pixeladdr(window.xbegin, y));
        for (int x = window.xbegin; x < window.xend; ++x, rgba += 4, ++z, src += n) {
            for (int c = 0; c < ncolor; ++c)
                rgba[c] = src[color[c]];
            if (depth >= 0)
                *z = src[depth];
        }
    }, by_rows(0));
}

/// Alpha 1 everywhere: colour read without alpha is opaque.
void set_opaque(Layer& layer)
{
    const ROI window = layer.color.roi();
    parallel_for(window.ybegin, window.yend, [&](int y) {
        float* rgba = static_cast<float*>(layer.color.pixeladdr(window.xbegin, y));
        for (int x = 0; x < window.width(); ++x)
            rgba[4 * x + 3] = 1.0f;
    }, by_rows(0));
}

/// A layer decoded straight from an EXR: colour from one part and, unless
/// `depth_part` is null, depth from the same part or another one, over the
/// colour part's data window.
bool decode_layer(const ExrInput& exr, const std::string& filename, const std::string& name,
                  const Part& color_part, const Part* depth_part, Layer& layer,
                  std::string& error)
{
    const ROI window = color_part.spec.roi();
    if (!allocate_layer(name, window, color_part.spec, layer, filename, error))
        return false;
    const ImageSpec& cs = color_part.spec;
    const size_t width = size_t(window.width());
    float* rgba = static_cast<float*>(layer.color.localpixels());
    float* z = static_cast<float*>(layer.depth.localpixels());
    std::vector<ChannelTarget> targets;
    for (int c = 0; c < 4; ++c)
        if (color_part.channels.color[c] >= 0)
            targets.push_back({ cs.channelnames[color_part.channels.color[c]], rgba + c, 4, 4 * width });
    if (depth_part) {
        const std::string depth_name = depth_part->spec.channelnames[depth_part->channels.depth];
        const ROI depth_window = depth_part->spec.roi();
        if (depth_part->subimage == color_part.subimage) {
            targets.push_back({ depth_name, z, 1, width });
        } else if (depth_window == window) {
            if (!exr.read(depth_part->subimage, window, { { depth_name, z, 1, width } }, error, 0))
                return false;
        } else {
            ImageBuf depth = depth_image(depth_window, depth_part->spec);
            if (!exr.read(depth_part->subimage, depth_window,
                          { { depth_name, static_cast<float*>(depth.localpixels()), 1,
                              size_t(depth_window.width()) } },
                          error, 0))
                return false;
            lay_depth(layer, depth, 0);
        }
    }
    return exr.read(color_part.subimage, window, targets, error, 0);
}

}  // namespace

bool read_pixels(ImageInput& in, const Part& part, ImageBuf& pixels,
                 const std::string& filename, std::string& error)
{
    ImageSpec all(part.spec.roi(), TypeFloat);
    all.nchannels    = part.spec.nchannels;
    all.channelnames = part.spec.channelnames;
    all.full_x      = part.spec.full_x;
    all.full_y      = part.spec.full_y;
    all.full_width  = part.spec.full_width;
    all.full_height = part.spec.full_height;
    pixels.reset(all);
    if (!in.read_image(part.subimage, 0, 0, part.spec.nchannels, TypeFloat,
                       pixels.localpixels())) {
        error = format("{}: {}: {}", filename, part.label,
                       Strutil::replace(in.geterror(), "\n", " ", true));
        return false;
    }
    return true;
}

void lay_depth(Layer& layer, const ImageBuf& depth, int channel)
{
    const ROI window       = layer.depth.roi();
    const ROI depth_window = depth.roi();
    parallel_for(window.ybegin, window.yend, [&](int y) {
        float* z = static_cast<float*>(layer.depth.pixeladdr(window.xbegin, y));
        for (int x = window.xbegin; x < window.xend; ++x, ++z)
            *z = depth_window.contains(x, y)
                     ? static_cast<const float*>(depth.pixeladdr(x, y))[channel]
                     : 0.0f;
    }, by_rows(0));
}

ImageBuf depth_image(const ROI& window, const ImageSpec& from)
{
    ImageSpec spec(window, TypeFloat);
    spec.nchannels    = 1;
    spec.channelnames = { "Z" };
    spec.full_x       = from.full_x;
    spec.full_y       = from.full_y;
    spec.full_width   = from.full_width;
    spec.full_height  = from.full_height;
    return ImageBuf(spec, InitializePixels::No);
}

bool read_layer(const ExrInput& exr, ImageInput& in, const std::string& filename,
                const std::string& name, const Part& color_part, const Part* depth_part,
                Layer& layer, std::string& error)
{
    if (exr.is_open()) {
        if (!decode_layer(exr, filename, name, color_part, depth_part, layer, error))
            return false;
    } else {
        ImageBuf color, depth;
        const bool same_part = depth_part && depth_part->subimage == color_part.subimage;
        if (!read_pixels(in, color_part, color, filename, error)
            || !allocate_layer(name, color.roi(), color_part.spec, layer, filename, error))
            return false;
        copy_layer(layer, color, color_part.channels.color,
                   same_part ? color_part.channels.depth : -1);
        if (depth_part && !same_part) {
            if (!read_pixels(in, *depth_part, depth, filename, error))
                return false;
            lay_depth(layer, depth, depth_part->channels.depth);
        }
    }
    if (!color_part.channels.has_alpha())
        set_opaque(layer);
    return true;
}

bool read_data_channels(const ExrInput& exr, ImageInput& in, const std::string& filename,
                        const Part& part, const std::vector<std::string>& names, Layer& layer,
                        std::string& error)
{
    std::vector<std::string> present;
    std::vector<int> indices;
    for (const std::string& name : names)
        if (const int c = part.spec.channelindex(name); c >= 0) {
            present.push_back(name);
            indices.push_back(c);
        }
    if (present.empty())
        return true;
    const ROI window = part.spec.roi();
    ImageSpec spec = depth_image(window, part.spec).spec();
    spec.nchannels = int(present.size());
    spec.channelnames = present;
    auto data = std::make_shared<ImageBuf>(spec, InitializePixels::No);
    if (exr.is_open()) {
        const size_t n = present.size();
        float* origin = static_cast<float*>(data->localpixels());
        std::vector<ChannelTarget> targets;
        for (size_t c = 0; c < n; ++c)
            targets.push_back({ present[c], origin + c, n, n * size_t(window.width()) });
        if (!exr.read(part.subimage, window, targets, error, 0))
            return false;
    } else {
        ImageBuf all;
        if (!read_pixels(in, part, all, filename, error))
            return false;
        if (!ImageBufAlgo::channels(*data, all, int(indices.size()), indices.data())) {
            error = format("{}: {}: {}", filename, part.label, data->geterror());
            return false;
        }
    }
    layer.data = std::move(data);
    return true;
}

}  // namespace defocus
