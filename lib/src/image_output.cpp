#include <defocus/image_output.h>

#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

namespace defocus {

using namespace OIIO;

namespace {

std::string temporary_name(const std::string& filename)
{
    const std::string dir = Filesystem::parent_path(filename);
    const std::string name = Strutil::fmt::format(
        ".{}.{}.tmp{}", Filesystem::filename(filename), getpid(),
        Filesystem::extension(filename));
    return dir.empty() ? name : dir + "/" + name;
}

/// Renames the complete temporary file over `filename`, or removes it.
bool commit(const std::string& tmp, const std::string& filename, std::string& error)
{
    std::string rename_error;
    if (Filesystem::rename(tmp, filename, rename_error))
        return true;
    Filesystem::remove(tmp);
    error = Strutil::fmt::format("{}: {}", filename, rename_error);
    return false;
}

}  // namespace

bool write_atomic(const std::string& filename,
                  const std::function<bool(ImageOutput&, const std::string&)>& write,
                  std::string& error)
{
    auto fail = [&](const std::string& why) {
        error = Strutil::fmt::format("{}: {}", filename,
                                     Strutil::replace(why, "\n", " ", true));
        return false;
    };
    auto out = ImageOutput::create(filename);
    if (!out)
        return fail(OIIO::geterror().empty() ? "no format writes this file type"
                                             : OIIO::geterror());
    const std::string tmp = temporary_name(filename);
    if (!write(*out, tmp) || !out->close()) {
        const std::string why = out->geterror();
        out.reset();
        Filesystem::remove(tmp);
        return fail(why.empty() ? "cannot write" : why);
    }
    out.reset();
    return commit(tmp, filename, error);
}

bool write_text_atomic(const std::string& filename, const std::string& text,
                       std::string& error)
{
    const std::string tmp = temporary_name(filename);
    if (!Filesystem::write_text_file(tmp, text)) {
        Filesystem::remove(tmp);
        error = filename + ": cannot write";
        return false;
    }
    return commit(tmp, filename, error);
}

bool write_image_atomic(const ImageBuf& image, const std::string& filename,
                        TypeDesc type, const std::string& compression,
                        std::string& error)
{
    ImageSpec spec = image.spec();
    if (type != TypeUnknown) {
        spec.set_format(type);
        spec.channelformats.clear();
    }
    if (!compression.empty())
        spec.attribute("compression", compression);
    return write_atomic(filename, [&](ImageOutput& out, const std::string& tmp) {
        if (out.supports("displaywindow"))
            return out.open(tmp, spec) && image.write(&out);
        // Formats without a display window (PNG, JPEG, ...) get the picture
        // a viewer shows: the display window.
        ImageBuf framed;
        ImageBufAlgo::crop(framed, image,
                           ROI(spec.full_x, spec.full_x + spec.full_width, spec.full_y,
                               spec.full_y + spec.full_height, 0, 1, 0, spec.nchannels));
        ImageSpec framed_spec = spec;
        framed_spec.set_roi(ROI(0, spec.full_width, 0, spec.full_height));
        framed_spec.full_x = framed_spec.full_y = 0;
        framed.specmod().x = framed.specmod().y = 0;
        framed.specmod().full_x = framed.specmod().full_y = 0;
        return out.open(tmp, framed_spec) && framed.write(&out);
    }, error);
}

bool write_layers_atomic(const std::vector<Layer>& layers, const ImageSpec& scene_spec,
                         const std::string& filename, std::string& error)
{
    if (layers.empty()) {
        error = filename + ": the scene has no layers to write";
        return false;
    }
    std::vector<ImageSpec> specs;
    std::vector<ImageBuf> parts;
    for (const Layer& layer : layers) {
        ImageBuf part;
        ImageBufAlgo::channel_append(part, layer.color, layer.depth);
        ImageSpec spec = scene_spec;
        spec.set_roi(part.roi());
        spec.deep = false;
        spec.nchannels = 5;
        spec.set_format(TypeFloat);
        spec.channelformats.clear();
        spec.channelnames = { "R", "G", "B", "A", "Z" };
        spec.alpha_channel = 3;
        spec.z_channel = 4;
        erase_part_attributes(spec);
        spec.attribute("name", layer.name);
        specs.push_back(spec);
        parts.push_back(std::move(part));
    }
    return write_atomic(filename, [&](ImageOutput& out, const std::string& tmp) {
        if (!out.supports("multiimage")) {
            out.errorfmt("cannot hold several layers: write an .exr");
            return false;
        }
        if (!out.open(tmp, int(specs.size()), specs.data()))
            return false;
        for (size_t i = 0; i < parts.size(); ++i)
            if ((i > 0 && !out.open(tmp, specs[i], ImageOutput::AppendSubimage))
                || !out.write_image(TypeFloat, parts[i].localpixels()))
                return false;
        return true;
    }, error);
}

}  // namespace defocus
