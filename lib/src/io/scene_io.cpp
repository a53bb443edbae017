#include <defocus/io/scene_io.h>

#include <cstdio>
#include <map>
#include <memory>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include <defocus/error_line.h>
#include <defocus/io/image_input.h>
#include <defocus/shot/setting_words.h>

#include "io/exr_input.h"
#include "io/part_channels.h"
#include "io/part_layer.h"
#include "util/parallel_rows.h"

namespace defocus {

using namespace OIIO;
using Strutil::fmt::format;

namespace {

/// What one file holds for the scene, chosen from its headers alone.
struct FileLayout {
    std::vector<Part> parts;      ///< of the chosen view, and of no view
    std::vector<size_t> complete; ///< parts with colour and depth: layers or one flat render
    int joined_color = -1;        ///< else a beauty part ...
    int joined_depth = -1;        ///< ... and a depth part: one flat render
    std::string depth_file;       ///< or the beauty part's depth in another file
    ROI data_window;              ///< the union of what is read

    /// The first part's header: display window, metadata.
    const ImageSpec& first() const { return parts.front().spec; }
};

/// Opens a file as OIIO reads it. An EXR's headers are first checked by
/// OpenEXR's core library, kept in `exr` (when given) to decode its pixels:
/// OpenImageIO 2.4 crashes or hangs on some corrupt EXRs that it rejects.
std::unique_ptr<ImageInput> open_file(const std::string& filename, ExrInput* exr,
                                      const MemoryLimit& limit, std::string& error)
{
    if (const char* why = not_a_file(filename)) {
        error = filename + ": " + why;
        return nullptr;
    }
    ExrInput headers_only;
    if (is_openexr_file(filename) && !(exr ? exr : &headers_only)->open(filename, error, limit))
        return nullptr;
    auto in = ImageInput::open(filename);
    if (!in) {
        std::string why = OIIO::geterror();
        if (why.empty())
            why = "not an image file OpenImageIO can read";
        error = error_about(filename, Strutil::replace(why, "\n", " ", true));
        return in;
    }
    // Decided once, from what was opened: a file rewritten between the two
    // opens must not reach OpenImageIO's EXR reader unchecked, nor the
    // checked reader unopened.
    const bool checked = exr ? exr->is_open() : headers_only.is_open();
    if ((in->format_name() == std::string("openexr")) != checked) {
        error = filename + ": changed while being read";
        return nullptr;
    }
    return in;
}

/// The parts of the chosen view (the first part's when none is chosen),
/// and those that belong to no view.
bool parts_of_view(ImageInput& in, const std::string& filename, const ReadOptions& options,
                   std::vector<Part>& parts, std::string& error)
{
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
                    ? format("{}: has no views, so {} does not apply", filename,
                             mention("view", options.view))
                    : format("{}: no view '{}' (views: {})", filename, options.view,
                             Strutil::join(views, ", "));
        return false;
    }
    if (parts.empty()) {
        error = filename + ": has no image parts";
        return false;
    }
    return true;
}

/// Where --depth points: a channel of the file's parts, or else a file
/// (layout.depth_file).
bool find_depth_source(const std::string& filename, const ReadOptions& options,
                       FileLayout& layout, bool& depth_is_channel, std::string& error)
{
    depth_is_channel = false;
    for (const Part& part : layout.parts)
        depth_is_channel |= !options.depth.empty() && part.spec.channelindex(options.depth) >= 0;
    if (!options.depth.empty() && !depth_is_channel) {
        if (!Filesystem::is_regular(options.depth)) {
            error = format("{}: {}: no such channel (channels: {}) and no such file",
                           filename, mention("depth", options.depth),
                           Strutil::join(layout.parts.front().spec.channelnames, ","));
            return false;
        }
        layout.depth_file = options.depth;
    }

    return true;
}

/// Each part's channels, and the part among the complete layers (colour and
/// depth), the colour-only or the depth-only parts.
bool sort_parts(const std::string& filename, const ReadOptions& options, bool depth_is_channel,
                FileLayout& layout, std::vector<size_t>& color_only,
                std::vector<size_t>& depth_only, std::string& error)
{
    for (size_t i = 0; i < layout.parts.size(); ++i) {
        Part& part = layout.parts[i];
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
        Channels& c = part.channels;
        if (!options.depth.empty())
            c.depth = depth_is_channel ? part.spec.channelindex(options.depth) : -1;
        // Alpha as depth gave a transparent frame and exit 0.
        for (int k = 0; k < 4 && c.depth >= 0; ++k)
            if (c.color[k] == c.depth) {
                error = format("{}: {}: that is the {} channel of {}, not a depth", filename,
                               mention("depth", options.depth), k == 3 ? "alpha" : "colour",
                               part.label);
                return false;
            }
        if (part.spec.deep && c.has_color() && !c.has_alpha()) {
            error = format("{}: {} is deep and has no A channel: deep samples need their "
                           "coverage", filename, part.label);
            return false;
        }
        if (c.has_color() && c.has_depth())
            layout.complete.push_back(i);
        else if (c.has_color())
            color_only.push_back(i);
        else if (c.has_depth() && !part.spec.deep)
            depth_only.push_back(i);
    }
    return true;
}

/// A file of no complete layers, or whose depth --depth FILE gives: its
/// colour part joined with a depth part or the depth file, as one flat
/// render.
bool join_flat_render(const std::string& filename, const ReadOptions& options,
                      FileLayout& layout, const std::vector<size_t>& color_only,
                      const std::vector<size_t>& depth_only, std::string& error)
{
    const std::vector<Part>& parts = layout.parts;
    if (!layout.depth_file.empty()) {
        // A beauty part, its depth in another file.
        if (color_only.size() != 1 || parts[color_only[0]].spec.deep) {
            error = format("{}: {} gives one flat render its depth, and this file {}",
                           filename, mention("depth", "FILE"),
                           color_only.empty()                ? "has no R,G,B channels"
                           : parts[color_only[0]].spec.deep ? "is deep"
                                                             : "has several colour parts");
            return false;
        }
        layout.joined_color = int(color_only[0]);
        layout.data_window  = parts[color_only[0]].spec.roi();
    } else if (layout.complete.empty()) {
        // A beauty part and a depth part of the same view: one flat render.
        if (color_only.size() == 1 && depth_only.size() == 1 && !parts[color_only[0]].spec.deep) {
            layout.joined_color = int(color_only[0]);
            layout.joined_depth = int(depth_only[0]);
            layout.data_window  = parts[color_only[0]].spec.roi();
        } else if (color_only.size() > 1 && depth_only.size() == 1) {
            error = format("{}: several colour parts share one depth part: choose a view "
                           "with {}", filename, mention("view"));
            return false;
        } else {
            const Part& first = color_only.empty() ? parts.front() : parts[color_only.front()];
            const std::string missing =
                options.depth.empty() ? missing_channel(first.spec, options.layer) : options.depth;
            const bool no_depth = first.channels.has_color();
            const std::string remedy
                = !options.missing_depth_remedy.empty()
                      ? options.missing_depth_remedy
                      : format("give its depth with {} or {}", mention("depth", "FILE"),
                               mention("depth", "CHANNEL"));
            error = format("{}: {} has no {} channel (channels: {}){}", filename, first.label,
                           missing, Strutil::join(first.spec.channelnames, ","),
                           no_depth ? ": " + remedy : "");
            return false;
        }
    }
    return true;
}

/// Chooses the parts of one file that make the scene, from their headers.
bool choose_parts(ImageInput& in, const std::string& filename, const ReadOptions& options,
                  FileLayout& layout, std::string& error)
{
    bool depth_is_channel = false;
    std::vector<size_t> color_only, depth_only;
    if (!parts_of_view(in, filename, options, layout.parts, error)
        || !find_depth_source(filename, options, layout, depth_is_channel, error)
        || !sort_parts(filename, options, depth_is_channel, layout, color_only, depth_only,
                       error))
        return false;
    const std::vector<Part>& parts = layout.parts;
    for (size_t i : layout.complete)
        layout.data_window = roi_union(layout.data_window, parts[i].spec.roi());
    // Beside layers with depth, a part with colour and no depth has no
    // place among them: it used to be dropped without a word.
    if (!layout.complete.empty() && !color_only.empty() && layout.depth_file.empty()) {
        const Part& part = parts[color_only.front()];
        error = format("{}: {} has colour but no depth ({}), unlike the file's other layers: "
                       "give it a Z channel, or leave it out of the file",
                       filename, part.label, missing_channel(part.spec, options.layer));
        return false;
    }
    return join_flat_render(filename, options, layout, color_only, depth_only, error);
}

/// What reading a file's chosen parts will allocate, from their headers
/// (a deep part's samples are counted once its sample counts are read):
/// checked against the memory limit before anything is allocated.
bool fits_memory_limit(const FileLayout& layout, bool openexr, const std::string& filename,
                       const MemoryLimit& limit, std::string& error)
{
    double bytes = 0.0;
    auto flat = [&](const Part& part) {
        bytes += float_bytes(part.spec.image_pixels(), 5);  // the layer: RGBA + Z
        if (!openexr)  // and the file's channels, read first
            bytes += float_bytes(part.spec.image_pixels(), part.spec.nchannels);
    };
    for (size_t i : layout.complete)
        if (layout.parts[i].spec.deep)
            bytes += deep_table_bytes(layout.parts[i].spec.width, layout.parts[i].spec.height);
        else
            flat(layout.parts[i]);
    if (layout.joined_color >= 0)
        flat(layout.parts[layout.joined_color]);
    if (layout.joined_depth >= 0)
        bytes += float_bytes(layout.parts[layout.joined_depth].spec.image_pixels(),
                             openexr ? 1 : 4);
    if (limit.allows(bytes))
        return true;
    const ROI& w = layout.data_window;
    error = format("{}: {}", filename,
                   limit.exceeded(format("a data window of {}x{}", w.width(), w.height()), bytes));
    return false;
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

/// Lays a flat render's depth from its own file (--depth FILE) into `layer`:
/// the Z channel of the file's first part, or its only channel. The file
/// must share the render's display window (`render`).
bool read_depth_file(const std::string& filename, const ImageSpec& render,
                     const MemoryLimit& limit, Layer& layer, std::string& error)
{
    ExrInput exr;
    auto in = open_file(filename, &exr, limit, error);
    if (!in)
        return false;
    const Part part { 0, in->spec(), "part 0", {} };
    const ImageSpec& spec = part.spec;
    int channel = first_channel(spec, { "Z", "depth.Z", "Depth.Z" });
    if (channel < 0 && spec.nchannels == 1)
        channel = 0;
    if (spec.deep || channel < 0) {
        error = format("{}: {}: {} takes a flat image with a Z channel or one channel",
                       filename,
                       spec.deep ? "is a deep image"
                                 : format("has no Z channel (channels: {})",
                                          Strutil::join(spec.channelnames, ",")),
                       mention("depth"));
        return false;
    }
    if (!same_display_window(spec, render, filename, error))
        return false;
    const double bytes = float_bytes(spec.image_pixels(), exr.is_open() ? 1 : spec.nchannels);
    if (!limit.allows(bytes)) {
        error = format("{}: {}", filename,
                       limit.exceeded(format("a depth image of {}x{}", spec.width, spec.height),
                                      bytes));
        return false;
    }
    ImageBuf depth;
    if (exr.is_open()) {
        depth = depth_image(spec.roi(), spec);
        if (!exr.read(0, spec.roi(),
                      { { spec.channelnames[channel], static_cast<float*>(depth.localpixels()),
                             1, size_t(spec.width) } },
                      error, 0))
            return false;
        channel = 0;
    } else if (!read_pixels(*in, part, depth, filename, error)) {
        return false;
    }
    lay_depth(layer, depth, channel);
    return true;
}

/// Reads one file into `scene`: its layers, flat renders and deep images.
bool read_file(const std::string& filename, const ReadOptions& options,
               Scene& scene, std::string& error)
{
    ExrInput exr;
    auto in = open_file(filename, &exr, options.memory_limit, error);
    FileLayout layout;
    if (!in || !choose_parts(*in, filename, options, layout, error)
        || !fits_memory_limit(layout, exr.is_open(), filename, options.memory_limit, error))
        return false;
    auto layer_name = [](const Part& part, const char* fallback) -> std::string {
        return part.spec.get_string_attribute("name", format("{}{}", fallback, part.subimage));
    };
    // ImageBuf's move may throw, so a vector that grows copies its layers.
    (layout.complete.size() > 1 ? scene.layers : scene.flat).reserve(layout.complete.size() + 1);
    for (size_t i : layout.complete) {
        const Part& part = layout.parts[i];
        const Channels& c = part.channels;
        if (part.spec.deep) {
            DeepChannels names;
            for (int k = 0; k < 4; ++k)
                names.color[k] = part.spec.channelnames[c.color[k]];
            names.depth = part.spec.channelnames[c.depth];
            const int zback = first_channel(part.spec, { channel_name(c.prefix, "ZBack"), "ZBack" });
            if (zback >= 0)
                names.depth_back = part.spec.channelnames[zback];
            for (const std::string& name : options.data_channels)
                if (part.spec.channelindex(name) >= 0)
                    names.data.push_back(name);
            DeepImage image;
            image.name = layer_name(part, "deep");
            if (!read_deep_part(filename, part.subimage, names, options.memory_limit, image,
                                error))
                return false;
            scene.deep.push_back(std::move(image));
            continue;
        }
        Layer layer;
        if (!read_layer(exr, *in, filename, layer_name(part, "layer"), part, &part, layer, error)
            || !read_data_channels(exr, *in, filename, part, options.data_channels, layer, error))
            return false;
        (layout.complete.size() > 1 ? scene.layers : scene.flat).push_back(std::move(layer));
    }
    if (layout.joined_color >= 0) {
        const Part& color_part = layout.parts[layout.joined_color];
        const Part* depth_part =
            layout.joined_depth >= 0 ? &layout.parts[layout.joined_depth] : nullptr;
        const std::string name = color_part.spec.get_string_attribute("name", "beauty");
        Layer layer;
        if (!read_layer(exr, *in, filename, name, color_part, depth_part, layer, error)
            || !read_data_channels(exr, *in, filename, color_part, options.data_channels, layer,
                                   error))
            return false;
        if (!layout.depth_file.empty()) {
            if (!read_depth_file(layout.depth_file, color_part.spec, options.memory_limit, layer,
                                 error))
                return false;
            scene.notes.push_back("depth from " + layout.depth_file);
        }
        scene.flat.push_back(std::move(layer));
    }
    for (const Part& part : layout.parts)
        if (part.channels.has_color() && !part.channels.has_alpha()) {
            scene.notes.push_back(filename + ": no alpha channel, taken as opaque");
            break;
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
    // Data channels by name: the union of the images', 0 where one lacks it.
    for (const DeepImage& image : images)
        for (const std::string& name : image.data_names)
            if (std::find(merged.data_names.begin(), merged.data_names.end(), name)
                == merged.data_names.end())
                merged.data_names.push_back(name);
    const size_t ndata = merged.data_names.size();
    merged.data.assign(merged.samples.size() * ndata, 0.0f);
    std::map<const DeepImage*, std::vector<size_t>> places;  // of each image's data channels
    for (const DeepImage& image : images)
        for (const std::string& name : image.data_names)
            places[&image].push_back(size_t(
                std::find(merged.data_names.begin(), merged.data_names.end(), name)
                - merged.data_names.begin()));
    std::vector<uint64_t> fill(merged.offsets.begin(), merged.offsets.end() - 1);
    for_each_source_pixel([&](const DeepImage& image, int64_t p, int64_t q) {
        const std::vector<size_t>& at = places[&image];
        for (uint64_t i = image.offsets[p]; i < image.offsets[p + 1]; ++i) {
            const uint64_t to = fill[q]++;
            merged.samples[to] = image.samples[i];
            for (size_t c = 0; c < at.size(); ++c)
                merged.data[to * ndata + at[c]] = image.data[i * at.size() + c];
        }
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

namespace {

/// Depth in metres: every Z, and a deep sample's Z back, times `scale`.
void scale_depth(Scene& scene, float scale)
{
    for_each_content(scene,
        [&](Layer& layer) {
            const ROI roi = layer.depth.roi();
            parallel_for(roi.ybegin, roi.yend, [&](int y) {
                float* z = static_cast<float*>(layer.depth.pixeladdr(roi.xbegin, y));
                for (int x = 0; x < roi.width(); ++x)
                    z[x] *= scale;
            }, by_rows(0));
            return true;
        },
        [&](DeepImage& image) {
            for (DeepSample& s : image.samples) {
                s.z *= scale;
                s.zback *= scale;
            }
            return true;
        });
}

/// The bytes a scene's layers and deep samples take.
double content_bytes(const Scene& scene)
{
    double bytes = 0.0;
    for_each_content(scene,
        [&](const Layer& layer) {
            bytes += double(layer.color.spec().image_bytes()) + double(layer.depth.spec().image_bytes())
                     + (layer.data ? double(layer.data->spec().image_bytes()) : 0.0);
            return true;
        },
        [&](const DeepImage& image) {
            bytes += double(image.samples.size()) * sizeof(DeepSample)
                     + double(image.offsets.size()) * sizeof(uint64_t)
                     + double(image.data.size()) * sizeof(float);
            return true;
        });
    return bytes;
}

/// Checks that there are inputs, and that a depth file is given to one.
bool check_inputs(const std::vector<std::string>& filenames, const ReadOptions& options,
                  std::string& error)
{
    if (filenames.empty()) {
        error = "no input file";
        return false;
    }
    if (filenames.size() > 1 && Filesystem::is_regular(options.depth)) {
        error = format("{}: a depth file gives one flat render its depth, not {} inputs",
                       mention("depth", options.depth), filenames.size());
        return false;
    }
    return true;
}

}  // namespace

double declared_bytes(const std::vector<std::string>& filenames, const MemoryLimit& limit)
{
    double bytes = 0.0;
    std::string ignored;
    for (const std::string& filename : filenames) {
        auto in = open_file(filename, nullptr, limit, ignored);
        for (int subimage = 0; in && in->seek_subimage(subimage, 0); ++subimage)
            bytes += float_bytes(double(in->spec().image_pixels()), in->spec().nchannels);
    }
    return bytes;
}

bool read_scene_spec(const std::vector<std::string>& filenames, const ReadOptions& options,
                     ImageSpec& spec, std::string& error)
{
    if (!check_inputs(filenames, options, error))
        return false;
    ROI data_window;
    for (size_t f = 0; f < filenames.size(); ++f) {
        auto in = open_file(filenames[f], nullptr, options.memory_limit, error);
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
    if (!check_inputs(filenames, options, error))
        return false;
    // The limit holds for the frame: each file gets what the ones before it
    // left (each file alone under it could still add up past it).
    ReadOptions file_options = options;
    for (const std::string& filename : filenames) {
        Scene part;
        part.spec = scene.spec;
        if (!read_file(filename, file_options, part, error))
            return false;
        file_options.memory_limit = file_options.memory_limit.spent(content_bytes(part));
        if (scene.source.empty())
            scene.spec = part.spec;
        // Several files are the layers of one scene: a flat file is a layer.
        // (Reserved: ImageBuf's move may throw, so a growing vector copies.)
        auto& as_layers = filenames.size() > 1 ? scene.layers : scene.flat;
        as_layers.reserve(as_layers.size() + part.flat.size() + part.layers.size());
        scene.layers.reserve(scene.layers.size() + part.flat.size() + part.layers.size());
        for (Layer& layer : part.flat)
            as_layers.push_back(std::move(layer));
        for (Layer& layer : part.layers)
            scene.layers.push_back(std::move(layer));
        for (DeepImage& image : part.deep)
            scene.deep.push_back(std::move(image));
        for (std::string& note : part.notes)
            if (std::find(scene.notes.begin(), scene.notes.end(), note) == scene.notes.end())
                scene.notes.push_back(std::move(note));
        scene.source += (scene.source.empty() ? "" : " ") + filename;
    }
    if (scene.deep.size() > 1) {
        DeepImage merged = merge_deep(scene.deep);
        scene.deep.clear();
        scene.deep.push_back(std::move(merged));
    }
    ROI data_window;
    for_each_content(scene,
        [&](const Layer& layer) {
            data_window = roi_union(data_window, layer.color.roi());
            return true;
        },
        [&](const DeepImage& image) {
            data_window = roi_union(data_window, image.roi);
            return true;
        });
    scene.spec.set_roi(data_window);
    if (options.depth_scale != 1.0)
        scale_depth(scene, float(options.depth_scale));
    return true;
}

}  // namespace defocus
