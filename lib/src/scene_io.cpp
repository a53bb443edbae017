#include <defocus/scene_io.h>

#include <cstdio>
#include <memory>
#include <set>

#include <OpenEXR/ImfCheckFile.h>
#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

namespace defocus {

using namespace OIIO;
using Strutil::fmt::format;

namespace {

bool is_openexr(const std::string& filename)
{
    unsigned char magic[4] = { 0, 0, 0, 0 };
    if (FILE* f = Filesystem::fopen(filename, "rb")) {
        const size_t n = fread(magic, 1, 4, f);
        fclose(f);
        return n == 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31
               && magic[3] == 0x01;
    }
    return false;
}

std::string channel_name(const std::string& prefix, const std::string& channel)
{
    return prefix.empty() ? channel : prefix + "." + channel;
}

/// Where one part keeps a layer's colour and depth; -1 where it has none.
struct Channels {
    std::string prefix;  ///< of the colour channels
    int color[4] = { -1, -1, -1, -1 };
    int depth    = -1;

    bool has_color() const { return color[3] >= 0; }
    bool has_depth() const { return depth >= 0; }
};

/// The first channel of `names` the part has, or -1.
int first_channel(const ImageSpec& spec, const std::vector<std::string>& names)
{
    for (const std::string& n : names) {
        const int c = spec.channelindex(n);
        if (c >= 0)
            return c;
    }
    return -1;
}

/// Resolves the colour and depth channels of one part. Colour is R,G,B,A
/// under the chosen prefix (--layer, also with Blender's ".Combined"), or
/// plain, or the part's only prefixed set. Depth is Z next to the colour,
/// Blender's <viewlayer>.Depth.Z, or a depth pass named Z or depth.Z.
/// `error` is set when the choice is ambiguous.
Channels find_channels(const ImageSpec& spec, const std::string& layer,
                       std::string& error)
{
    std::vector<std::string> prefixes;
    if (!layer.empty()) {
        prefixes = { layer, layer + ".Combined" };
    } else {
        prefixes = { "" };
        std::set<std::string> seen;
        for (const std::string& n : spec.channelnames)
            if (Strutil::ends_with(n, ".R") && seen.insert(n).second)
                prefixes.push_back(n.substr(0, n.size() - 2));
    }
    Channels ch;
    std::vector<std::string> complete;
    for (const std::string& p : prefixes) {
        int c[4];
        const char* rgba[4] = { "R", "G", "B", "A" };
        bool all = true;
        for (int i = 0; i < 4; ++i)
            all &= (c[i] = spec.channelindex(channel_name(p, rgba[i]))) >= 0;
        if (!all)
            continue;
        complete.push_back(p);
        if (complete.size() == 1) {
            ch.prefix = p;
            std::copy(c, c + 4, ch.color);
        }
    }
    if (complete.size() > 1 && !complete.front().empty())
        error = format("it holds several layers ({}): choose one with --layer NAME",
                       Strutil::join(complete, ", "));

    std::string view_layer = ch.prefix;
    if (Strutil::ends_with(view_layer, ".Combined"))
        view_layer.resize(view_layer.size() - 9);
    std::vector<std::string> depth_names;
    if (!layer.empty())
        depth_names = { channel_name(layer, "Z"), channel_name(layer, "Depth.Z") };
    if (!ch.prefix.empty())
        depth_names.push_back(channel_name(ch.prefix, "Z"));
    if (!view_layer.empty())
        depth_names.push_back(channel_name(view_layer, "Depth.Z"));
    for (const char* n : { "Z", "depth.Z", "Depth.Z" })
        depth_names.emplace_back(n);
    ch.depth = first_channel(spec, depth_names);
    return ch;
}

/// The first of R,G,B,A,Z a part lacks, for messages.
std::string missing_channel(const ImageSpec& spec, const std::string& layer)
{
    for (const char* c : { "R", "G", "B", "A" })
        if (spec.channelindex(channel_name(layer, c)) < 0
            && spec.channelindex(channel_name(layer, std::string("Combined.") + c)) < 0)
            return channel_name(layer, c);
    return channel_name(layer, "Z");
}

struct Part {
    int subimage;
    ImageSpec spec;
    std::string label;
    Channels channels;
};

/// Reads every channel of a flat part as float.
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

/// A layer from the colour channels of one part and the depth channel of
/// another (or the same) part, over the colour part's data window, in one
/// pass. Depth outside the depth part's data window is 0, which sanitize()
/// treats as missing.
Layer make_layer(const std::string& name, const ImageBuf& color_part,
                 const int color[4], const ImageBuf& depth_part, int depth)
{
    const ImageSpec& from = color_part.spec();
    const ROI window      = color_part.roi();
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
    Layer layer;
    layer.name = name;
    layer.color.reset(color_spec);
    layer.depth.reset(depth_spec);
    const ROI depth_window = depth_part.roi();
    const bool same_part   = &depth_part == &color_part;
    parallel_for(window.ybegin, window.yend, [&](int y) {
        float* rgba = static_cast<float*>(layer.color.pixeladdr(window.xbegin, y));
        float* z    = static_cast<float*>(layer.depth.pixeladdr(window.xbegin, y));
        const float* src = static_cast<const float*>(color_part.pixeladdr(window.xbegin, y));
        const int n      = from.nchannels;
        for (int x = window.xbegin; x < window.xend; ++x, rgba += 4, ++z, src += n) {
            for (int c = 0; c < 4; ++c)
                rgba[c] = src[color[c]];
            if (same_part)
                *z = src[depth];
            else
                *z = depth_window.contains(x, y)
                         ? static_cast<const float*>(depth_part.pixeladdr(x, y))[depth]
                         : 0.0f;
        }
    });
    return layer;
}

bool read_deep(ImageInput& in, const Part& part, DeepImage& image,
               const std::string& filename, std::string& error)
{
    DeepData data;
    if (!in.read_native_deep_image(part.subimage, 0, data)) {
        error = format("{}: {}: {}", filename, part.label,
                       Strutil::replace(in.geterror(), "\n", " ", true));
        return false;
    }
    const Channels& ch = part.channels;
    const int zback = first_channel(part.spec, { channel_name(ch.prefix, "ZBack"), "ZBack" });
    image.name = part.spec.get_string_attribute("name", format("deep{}", part.subimage));
    image.roi  = part.spec.roi();
    const int64_t npixels = image.roi.npixels();
    if (data.pixels() != npixels) {
        error = format("{}: {}: deep data has {} pixels, expected {}", filename,
                       part.label, data.pixels(), npixels);
        return false;
    }
    image.offsets.assign(npixels + 1, 0);
    for (int64_t p = 0; p < npixels; ++p)
        image.offsets[p + 1] = image.offsets[p] + data.samples(p);
    image.samples.resize(image.offsets.back());
    for (int64_t p = 0; p < npixels; ++p)
        for (int s = 0, n = data.samples(p); s < n; ++s) {
            DeepSample& d = image.samples[image.offsets[p] + s];
            d.r = data.deep_value(p, ch.color[0], s);
            d.g = data.deep_value(p, ch.color[1], s);
            d.b = data.deep_value(p, ch.color[2], s);
            d.a = data.deep_value(p, ch.color[3], s);
            d.z = data.deep_value(p, ch.depth, s);
            d.zback = zback >= 0 ? data.deep_value(p, zback, s) : d.z;
        }
    return true;
}

/// What one file holds for the scene, chosen from its headers alone.
struct FileLayout {
    std::vector<Part> parts;      ///< of the chosen view, and of no view
    std::vector<size_t> complete; ///< parts with colour and depth: layers or one flat render
    int joined_color = -1;        ///< else a beauty part ...
    int joined_depth = -1;        ///< ... and a depth part: one flat render
    ROI data_window;              ///< the union of what is read

    /// The first part's header: display window, metadata.
    const ImageSpec& first() const { return parts.front().spec; }
};

/// Opens a file as OIIO reads it. EXRs are vetted first with OpenEXR's
/// own checker (the code behind exrcheck) when `vet`: OpenImageIO 2.4
/// crashes or hangs on some corrupt EXRs that it survives.
std::unique_ptr<ImageInput> open_file(const std::string& filename, bool vet,
                                      std::string& error)
{
    if (!Filesystem::exists(filename)) {
        error = filename + ": no such file";
        return nullptr;
    }
    if (Filesystem::is_directory(filename)) {
        error = filename + ": is a directory, not an image";
        return nullptr;
    }
    // checkOpenEXRFile returns true when it finds a problem.
    if (vet && is_openexr(filename)
        && Imf::checkOpenEXRFile(filename.c_str(), /*reduceMemory=*/true,
                                 /*reduceTime=*/true, /*enableCoreCheck=*/true)) {
        error = filename + ": corrupt or truncated OpenEXR file";
        return nullptr;
    }
    auto in = ImageInput::open(filename);
    if (!in) {
        std::string why = OIIO::geterror();
        if (why.empty())
            why = "not an image file OpenImageIO can read";
        error = format("{}: {}", filename, Strutil::replace(why, "\n", " ", true));
    }
    return in;
}

/// Chooses the parts of one file that make the scene, from their headers.
bool choose_parts(ImageInput& in, const std::string& filename, const ReadOptions& options,
                  FileLayout& layout, std::string& error)
{
    // The parts of the chosen view, and those that belong to no view.
    std::vector<Part>& parts = layout.parts;
    std::vector<std::string> views;
    std::string view = options.view;
    for (int s = 0; in.seek_subimage(s, 0); ++s) {
        ImageSpec spec = in.spec(s, 0);
        const std::string part_view = spec.get_string_attribute("view");
        if (!part_view.empty() && std::find(views.begin(), views.end(), part_view) == views.end())
            views.push_back(part_view);
        if (view.empty() && s == 0)
            view = part_view;
        if (!part_view.empty() && part_view != view)
            continue;
        const std::string name = spec.get_string_attribute("name");
        parts.push_back({ s, spec,
                          name.empty() ? format("part {}", s) : format("part {} '{}'", s, name),
                          {} });
    }
    if (!options.view.empty() && std::find(views.begin(), views.end(), options.view) == views.end()) {
        error = views.empty()
                    ? format("{}: has no views, so --view {} does not apply", filename, options.view)
                    : format("{}: no view '{}' (views: {})", filename, options.view,
                             Strutil::join(views, ", "));
        return false;
    }
    if (parts.empty()) {
        error = filename + ": has no image parts";
        return false;
    }

    std::vector<size_t> color_only, depth_only;
    for (size_t i = 0; i < parts.size(); ++i) {
        Part& part = parts[i];
        std::string ambiguity;
        part.channels = find_channels(part.spec, options.layer, ambiguity);
        if (!ambiguity.empty()) {
            error = format("{}: {}: {}", filename, part.label, ambiguity);
            return false;
        }
        if (part.spec.depth > 1) {
            error = format("{}: {} is a volume image", filename, part.label);
            return false;
        }
        const Channels& c = part.channels;
        if (c.has_color() && c.has_depth())
            layout.complete.push_back(i);
        else if (c.has_color())
            color_only.push_back(i);
        else if (c.has_depth() && !part.spec.deep)
            depth_only.push_back(i);
    }
    for (size_t i : layout.complete)
        layout.data_window = roi_union(layout.data_window, parts[i].spec.roi());

    if (layout.complete.empty()) {
        // A beauty part and a depth part of the same view: one flat render.
        if (color_only.size() == 1 && depth_only.size() == 1 && !parts[color_only[0]].spec.deep) {
            layout.joined_color = int(color_only[0]);
            layout.joined_depth = int(depth_only[0]);
            layout.data_window  = parts[color_only[0]].spec.roi();
        } else if (color_only.size() > 1 && depth_only.size() == 1) {
            error = format("{}: several colour parts share one depth part: choose a view "
                           "with --view", filename);
            return false;
        } else {
            const Part& first = color_only.empty() ? parts.front() : parts[color_only.front()];
            error = format("{}: {} has no {} channel (channels: {})", filename, first.label,
                           missing_channel(first.spec, options.layer),
                           Strutil::join(first.spec.channelnames, ","));
            return false;
        }
    }
    return true;
}

/// Checks that a file shares the display window of the scene's first.
bool same_display_window(const ImageSpec& first, const ImageSpec& scene,
                         const std::string& filename, std::string& error)
{
    if (first.full_x == scene.full_x && first.full_y == scene.full_y
        && first.full_width == scene.full_width && first.full_height == scene.full_height)
        return true;
    error = format("{}: display window {}x{}{:+d}{:+d} differs from the first input's {}x{}{:+d}{:+d}",
                   filename, first.full_width, first.full_height, first.full_x, first.full_y,
                   scene.full_width, scene.full_height, scene.full_x, scene.full_y);
    return false;
}

/// Reads one file into `scene`: its layers, flat renders and deep images.
bool read_file(const std::string& filename, const ReadOptions& options,
               Scene& scene, std::string& error)
{
    auto in = open_file(filename, /*vet=*/true, error);
    FileLayout layout;
    if (!in || !choose_parts(*in, filename, options, layout, error))
        return false;
    for (size_t i : layout.complete) {
        const Part& part = layout.parts[i];
        if (part.spec.deep) {
            DeepImage image;
            if (!read_deep(*in, part, image, filename, error))
                return false;
            scene.deep.push_back(std::move(image));
            continue;
        }
        ImageBuf pixels;
        if (!read_pixels(*in, part, pixels, filename, error))
            return false;
        const Channels& c = part.channels;
        const std::string name = part.spec.get_string_attribute(
            "name", format("layer{}", part.subimage));
        (layout.complete.size() > 1 ? scene.layers : scene.flat)
            .push_back(make_layer(name, pixels, c.color, pixels, c.depth));
    }
    if (layout.joined_color >= 0) {
        const Part& color_part = layout.parts[layout.joined_color];
        const Part& depth_part = layout.parts[layout.joined_depth];
        ImageBuf color, depth;
        if (!read_pixels(*in, color_part, color, filename, error)
            || !read_pixels(*in, depth_part, depth, filename, error))
            return false;
        scene.flat.push_back(make_layer(color_part.spec.get_string_attribute("name", "beauty"),
                                        color, color_part.channels.color, depth,
                                        depth_part.channels.depth));
    }
    if (scene.spec.nchannels == 0 || scene.spec.full_width == 0) {
        scene.spec = layout.first();
        return true;
    }
    return same_display_window(layout.first(), scene.spec, filename, error);
}

/// Deep images of one scene merged into one: every pixel's samples from all
/// of them, over the union of their data windows. Slicing then sorts each
/// pixel's samples by depth, so objects from different files interleave
/// correctly pixel by pixel.
DeepImage merge_deep(std::vector<DeepImage>& images)
{
    DeepImage merged;
    merged.name = images.front().name;
    for (const DeepImage& image : images)
        merged.roi = roi_union(merged.roi, image.roi);
    const int64_t n = merged.roi.npixels();
    merged.offsets.assign(n + 1, 0);
    auto for_each_source_pixel = [&](auto&& fn) {
        for (const DeepImage& image : images)
            for (int y = image.roi.ybegin; y < image.roi.yend; ++y)
                for (int x = image.roi.xbegin; x < image.roi.xend; ++x)
                    fn(image, image.pixel_index(x, y), merged.pixel_index(x, y));
    };
    for_each_source_pixel([&](const DeepImage& image, int64_t p, int64_t q) {
        merged.offsets[q + 1] += image.offsets[p + 1] - image.offsets[p];
    });
    for (int64_t q = 0; q < n; ++q)
        merged.offsets[q + 1] += merged.offsets[q];
    merged.samples.resize(merged.offsets.back());
    std::vector<uint64_t> fill(merged.offsets.begin(), merged.offsets.end() - 1);
    for_each_source_pixel([&](const DeepImage& image, int64_t p, int64_t q) {
        for (uint64_t i = image.offsets[p]; i < image.offsets[p + 1]; ++i)
            merged.samples[fill[q]++] = image.samples[i];
    });
    return merged;
}

}  // namespace

void erase_part_attributes(ImageSpec& spec)
{
    for (const char* part_only : { "name", "view", "oiio:subimages", "oiio:subimagename",
                                   "openexr:chunkCount" })
        spec.erase_attribute(part_only);
}

bool read_scene_spec(const std::vector<std::string>& filenames, const ReadOptions& options,
                     ImageSpec& spec, std::string& error)
{
    if (filenames.empty()) {
        error = "no input file";
        return false;
    }
    ROI data_window;
    for (size_t f = 0; f < filenames.size(); ++f) {
        auto in = open_file(filenames[f], /*vet=*/false, error);
        FileLayout layout;
        if (!in || !choose_parts(*in, filenames[f], options, layout, error))
            return false;
        if (f == 0)
            spec = layout.first();
        else if (!same_display_window(layout.first(), spec, filenames[f], error))
            return false;
        data_window = roi_union(data_window, layout.data_window);
    }
    spec.set_roi(data_window);
    return true;
}

bool read_scene(const std::vector<std::string>& filenames, const ReadOptions& options,
                Scene& scene, std::string& error)
{
    scene = Scene();
    if (filenames.empty()) {
        error = "no input file";
        return false;
    }
    for (const std::string& filename : filenames) {
        Scene part;
        part.spec = scene.spec;
        if (!read_file(filename, options, part, error))
            return false;
        if (scene.source.empty())
            scene.spec = part.spec;
        // Several files are the layers of one scene: a flat file is a layer.
        auto& as_layers = filenames.size() > 1 ? scene.layers : scene.flat;
        for (Layer& layer : part.flat)
            as_layers.push_back(std::move(layer));
        for (Layer& layer : part.layers)
            scene.layers.push_back(std::move(layer));
        for (DeepImage& image : part.deep)
            scene.deep.push_back(std::move(image));
        scene.source += (scene.source.empty() ? "" : " ") + filename;
    }
    if (scene.deep.size() > 1) {
        DeepImage merged = merge_deep(scene.deep);
        scene.deep.clear();
        scene.deep.push_back(std::move(merged));
    }
    ROI data_window;
    for (const auto* list : { &scene.layers, &scene.flat })
        for (const Layer& layer : *list)
            data_window = roi_union(data_window, layer.color.roi());
    for (const DeepImage& image : scene.deep)
        data_window = roi_union(data_window, image.roi);
    scene.spec.set_roi(data_window);
    return true;
}

}  // namespace defocus
