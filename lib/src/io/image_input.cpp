#include <defocus/io/image_input.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

namespace defocus {

using namespace OIIO;

bool read_image_file(const std::string& filename, const std::string& what, ImageBuf& dst,
                     std::string& error)
{
    auto fail = [&](const std::string& why) {
        error = Strutil::fmt::format("{}: cannot read {}: {}", filename, what,
                                     Strutil::replace(why, "\n", " ", true));
        return false;
    };
    if (!Filesystem::is_regular(filename))  // a device or a pipe would be read forever
        return fail(Filesystem::exists(filename) ? "not a regular file" : "no such file");
    auto in = ImageInput::open(filename);
    if (!in) {
        const std::string why = OIIO::geterror();  // geterror() clears it: read once
        return fail(why.empty() ? "no format reads it" : why);
    }
    ImageSpec spec = in->spec();
    spec.set_format(TypeFloat);
    spec.channelformats.clear();
    ImageBuf image(spec);
    if (!in->read_image(0, 0, 0, spec.nchannels, TypeFloat, image.localpixels())) {
        const std::string why = in->geterror();
        return fail(why.empty() ? "unreadable" : why);
    }
    dst = std::move(image);
    return true;
}

}  // namespace defocus
