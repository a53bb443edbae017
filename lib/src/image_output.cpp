#include <defocus/image_output.h>

#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

namespace defocus {

using namespace OIIO;

namespace {

std::string temporary_name(const std::string& filename)
{
    const std::string dir = Filesystem::parent_path(filename);
    const std::string stem = Filesystem::filename(filename);
    const std::string ext = Filesystem::extension(filename);
    const std::string name = Strutil::fmt::format(".{}.{}.tmp{}", stem, getpid(), ext);
    return dir.empty() ? name : dir + "/" + name;
}

}  // namespace

bool write_image_atomic(const ImageBuf& image, const std::string& filename,
                        TypeDesc type, const std::string& compression,
                        std::string& error)
{
    auto fail = [&](const std::string& why) {
        error = Strutil::fmt::format("{}: {}", filename, Strutil::replace(why, "\n", " ", true));
        return false;
    };
    auto out = ImageOutput::create(filename);
    if (!out)
        return fail(OIIO::geterror().empty() ? "no format writes this file type"
                                             : OIIO::geterror());
    ImageSpec spec = image.spec();
    if (type != TypeUnknown) {
        spec.set_format(type);
        spec.channelformats.clear();
    }
    if (!compression.empty())
        spec.attribute("compression", compression);
    const std::string tmp = temporary_name(filename);
    bool ok = out->open(tmp, spec)
              && image.write(out.get())
              && out->close();
    if (!ok) {
        std::string why = out->geterror();
        if (why.empty())
            why = image.geterror();
        out.reset();
        Filesystem::remove(tmp);
        return fail(why.empty() ? "cannot write" : why);
    }
    std::string rename_error;
    if (!Filesystem::rename(tmp, filename, rename_error)) {
        Filesystem::remove(tmp);
        return fail(rename_error);
    }
    return true;
}

}  // namespace defocus
