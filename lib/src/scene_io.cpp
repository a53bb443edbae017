#include <defocus/scene_io.h>

#include <cstdio>

#include <OpenEXR/ImfCheckFile.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

namespace defocus {

using namespace OIIO;

namespace {

std::string part_label(const ImageSpec& spec, int subimage)
{
    const std::string name = spec.get_string_attribute("name");
    return name.empty() ? Strutil::fmt::format("part {}", subimage)
                        : Strutil::fmt::format("part {} '{}'", subimage, name);
}

bool read_layer(ImageInput& in, int subimage, const std::string& filename,
                Layer& layer, std::string& error)
{
    const ImageSpec spec = in.spec(subimage);
    const std::string label = part_label(spec, subimage);
    if (spec.deep) {
        error = Strutil::fmt::format("{}: {} is a deep image, which this version cannot read",
                                     filename, label);
        return false;
    }
    if (spec.depth > 1) {
        error = Strutil::fmt::format("{}: {} is a volume image", filename, label);
        return false;
    }
    int channel[5];
    const char* names[5] = { "R", "G", "B", "A", "Z" };
    for (int c = 0; c < 5; ++c) {
        channel[c] = spec.channelindex(names[c]);
        if (channel[c] < 0) {
            error = Strutil::fmt::format("{}: {} has no {} channel (channels: {})",
                                         filename, label, names[c],
                                         Strutil::join(spec.channelnames, ","));
            return false;
        }
    }
    ImageSpec all(spec.roi(), TypeFloat);
    all.nchannels    = spec.nchannels;
    all.channelnames = spec.channelnames;
    all.full_x      = spec.full_x;
    all.full_y      = spec.full_y;
    all.full_width  = spec.full_width;
    all.full_height = spec.full_height;
    ImageBuf pixels(all);
    if (!in.read_image(subimage, 0, 0, spec.nchannels, TypeFloat,
                       pixels.localpixels())) {
        error = Strutil::fmt::format("{}: {}: {}", filename, label,
                                     in.geterror());
        return false;
    }
    layer.name = spec.get_string_attribute("name",
                                           Strutil::fmt::format("layer{}", subimage));
    const std::string color_names[] = { "R", "G", "B", "A" }, depth_name[] = { "Z" };
    ImageBufAlgo::channels(layer.color, pixels, 4, cspan<int>(channel, 4), {},
                           color_names);
    ImageBufAlgo::channels(layer.depth, pixels, 1, cspan<int>(channel + 4, 1), {},
                           depth_name);
    layer.color.specmod().alpha_channel = 3;
    return true;
}

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

}  // namespace

bool read_scene(const std::string& filename, Scene& scene, std::string& error)
{
    if (!Filesystem::exists(filename)) {
        error = filename + ": no such file";
        return false;
    }
    if (Filesystem::is_directory(filename)) {
        error = filename + ": is a directory, not an image";
        return false;
    }
    // OpenImageIO 2.4 crashes or hangs on some corrupt EXRs; OpenEXR's own
    // checker (the code behind exrcheck) survives them, so it vets every
    // EXR before OIIO reads it. It returns true when it finds a problem.
    if (is_openexr(filename)
        && Imf::checkOpenEXRFile(filename.c_str(), /*reduceMemory=*/true,
                                 /*reduceTime=*/true, /*enableCoreCheck=*/true)) {
        error = filename + ": corrupt or truncated OpenEXR file";
        return false;
    }
    auto in = ImageInput::open(filename);
    if (!in) {
        std::string why = OIIO::geterror();
        if (why.empty())
            why = "not an image file OpenImageIO can read";
        error = Strutil::fmt::format("{}: {}", filename,
                                     Strutil::replace(why, "\n", " "));
        return false;
    }
    scene.source = filename;
    scene.spec   = in->spec(0, 0);
    scene.layers.clear();
    ROI data_window;
    for (int subimage = 0; in->seek_subimage(subimage, 0); ++subimage) {
        Layer layer;
        if (!read_layer(*in, subimage, filename, layer, error))
            return false;
        data_window = roi_union(data_window, layer.color.roi());
        scene.layers.push_back(std::move(layer));
    }
    if (scene.layers.empty()) {
        error = filename + ": has no image parts";
        return false;
    }
    scene.spec.set_roi(data_window);
    return true;
}

}  // namespace defocus
