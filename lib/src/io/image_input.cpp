#include <defocus/io/image_input.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include "io/exr_input.h"

namespace defocus {

using namespace OIIO;

const char* not_a_file(const std::string& filename)
{
    if (!Filesystem::exists(filename))
        return "no such file";
    if (Filesystem::is_directory(filename))
        return "is a directory, not an image";
    if (!Filesystem::is_regular(filename))
        return "not a regular file";
    return nullptr;
}

bool read_image_file(const std::string& filename, const std::string& what, ImageBuf& dst,
                     std::string& error)
{
    auto fail = [&](const std::string& why) {
        error = Strutil::fmt::format("{}: cannot read {}: {}", filename, what,
                                     Strutil::replace(why, "\n", " ", true));
        return false;
    };
    if (const char* why = not_a_file(filename))
        return fail(why);
    // OpenImageIO's EXR reader allocates what a damaged header asks for
    // before it finds the file short: OpenEXR's core library checks first.
    std::string damage;
    ExrInput headers;
    if (is_openexr_file(filename) && !headers.open(filename, damage))
        return fail(damage);
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
