#include <defocus/io/image_output.h>

#include <sys/resource.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <vector>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <defocus/io/image_input.h>
#include <defocus/optics/depth_kind.h>

#include "io/exr_input.h"
#include "io/half_pixels.h"
#include "io/temporary_files.h"
#include "util/file_identity.h"

namespace defocus {

using namespace OIIO;

namespace {

/// The compression names each format that takes one knows (an optional
/// ":quality" may follow, e.g. dwaa:45).
const std::map<std::string, std::vector<std::string>>& compressions()
{
    static const std::map<std::string, std::vector<std::string>> names = {
        { "openexr", { "none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa",
                       "dwab" } },
        { "tiff", { "none", "lzw", "zip", "packbits", "jpeg" } },
        { "png", { "zip" } },
        { "jpeg", { "jpeg" } },
    };
    return names;
}

/// Whether a PNG or JPEG file lacks the marker that ends every complete
/// one (a PNG's IEND chunk, a JPEG's EOI): cut short. Checked before such a
/// file is decoded: libpng reports a file cut short by a longjmp, which
/// leaks what OpenImageIO's reader held (LeakSanitizer finds it).
bool cut_before_end_marker(const std::string& filename)
{
    static const std::string png_magic = "\x89PNG", jpeg_magic = "\xFF\xD8\xFF";
    static const std::string png_end("\0\0\0\0IEND\xAE\x42\x60\x82", 12), jpeg_end = "\xFF\xD9";
    std::string head(4, '\0'), tail(12, '\0');
    FILE* f = Filesystem::fopen(filename, "rb");
    if (!f)
        return false;
    const bool read = std::fread(head.data(), 1, 4, f) == 4 && std::fseek(f, -12, SEEK_END) == 0
                      && std::fread(tail.data(), 1, 12, f) == 12;
    std::fclose(f);
    if (!read)
        return Strutil::starts_with(head, png_magic) || Strutil::starts_with(head, jpeg_magic);
    return (Strutil::starts_with(head, png_magic) && tail != png_end)
           || (Strutil::starts_with(head, jpeg_magic) && !Strutil::ends_with(tail, jpeg_end));
}

}  // namespace

bool check_overwrites(const std::vector<std::string>& read,
                      const std::vector<std::string>& written, std::string& error)
{
    std::map<FileIdentity, const std::string*> inputs;
    for (const std::string& file : read)
        if (const std::optional<FileIdentity> id = FileIdentity::of(file))
            inputs.emplace(*id, &file);
    for (const std::string& file : written) {
        const std::optional<FileIdentity> id = file.empty() ? std::nullopt
                                                            : FileIdentity::of(file);
        const auto input = id ? inputs.find(*id) : inputs.end();
        if (input != inputs.end()) {
            error = Strutil::fmt::format("{}: would overwrite the input {}", file,
                                         *input->second);
            return false;
        }
    }
    return true;
}

bool same_path(const std::string& a, const std::string& b)
{
    std::error_code ec_a, ec_b;
    const std::filesystem::path pa = std::filesystem::weakly_canonical(a, ec_a);
    const std::filesystem::path pb = std::filesystem::weakly_canonical(b, ec_b);
    return ec_a || ec_b ? a == b : pa == pb;
}

bool written_with_settings(const std::string& filename, const std::string& hash,
                           std::string& why)
{
    if (!Filesystem::exists(filename)) {
        why = "does not exist";
        return false;
    }
    auto unreadable = [&](const std::string& reason) {
        why = "cannot be read (" + Strutil::replace(reason, "\n", " ", true) + ")";
        return false;
    };
    // An EXR is read by OpenEXR's core library alone, which checks its
    // headers before anything is allocated: OpenImageIO's reader
    // allocated what a damaged tile description asked for (found by
    // fuzzing: 10 s and gigabytes for a 100-byte file).
    ExrInput exr;
    std::string reason, recorded;
    const bool openexr = is_openexr_file(filename);
    if (openexr) {
        if (!exr.open(filename, reason))
            return unreadable(reason);
        recorded = exr.string_attribute("defocus:settingsHash");
    } else {
        if (cut_before_end_marker(filename)) {
            why = "is incomplete (it does not end as its format ends)";
            return false;
        }
        auto in = ImageInput::open(filename);
        if (!in)
            return unreadable(OIIO::geterror());
        recorded = in->spec().get_string_attribute("defocus:settingsHash");
    }
    if (recorded.empty()) {
        why = "has no defocus:settingsHash (not written by this defocus)";
        return false;
    }
    if (recorded != hash) {
        why = "was written with other settings (defocus:settingsHash " + recorded + ", now "
              + hash + ")";
        return false;
    }
    // Its header alone does not say it is whole: a copy cut short, or a
    // file system that lost its end, has the same header.
    std::string damage;
    ImageBuf pixels;
    const bool whole = openexr ? exr.complete(damage)
                               : read_image_file(filename, "the output", pixels, damage);
    if (!whole) {
        why = "is incomplete (" + Strutil::replace(damage, "\n", " ", true) + ")";
        return false;
    }
    return true;
}

const std::set<std::string>& deep_compressions()
{
    // OpenImageIO 2.4 writes a deep EXR with every other as zips.
    static const std::set<std::string> names = { "none", "zips" };
    return names;
}

std::string deep_compression(const std::string& given, const std::string& inherited)
{
    if (!given.empty())
        return given;
    return deep_compressions().count(inherited) ? inherited : "zips";
}

bool check_output(const std::string& filename, const std::string& compression,
                  std::string& error, bool deep, const std::string& named_channels)
{
    auto fail = [&](const std::string& why) {
        error = Strutil::fmt::format("{}: {}", filename, why);
        return false;
    };
    const std::string parent = Filesystem::parent_path(filename);
    const std::string folder = parent.empty() ? "." : parent;
    if (!Filesystem::is_directory(folder))
        return fail(Strutil::fmt::format("the folder {} does not exist", folder));
    if (::access(folder.c_str(), W_OK | X_OK) != 0)
        return fail(Strutil::fmt::format("the folder {} is not writable", folder));
    if (const std::string problem = replace_problem(filename); !problem.empty())
        return fail(problem);
    auto out = ImageOutput::create(filename);
    if (!out) {
        OIIO::geterror();  // cleared: our message says it better
        const std::string ext = Filesystem::extension(filename);
        return fail(ext.empty() ? "no extension to tell the image format (e.g. .exr)"
                                : Strutil::fmt::format("no image format writes {} files", ext));
    }
    const std::string format = out->format_name();
    if (deep && !out->supports("deepdata"))
        return fail(Strutil::fmt::format("a deep result is written as OpenEXR (.exr), not {}",
                                         format));
    // TIFF writes no channel names, JPEG drops channels past the fourth,
    // and PNG refuses them only once the frame is rendered.
    if (!named_channels.empty() && format != "openexr")
        return fail(Strutil::fmt::format(
            "{} files do not keep channel names, which {} needs: write OpenEXR (.exr)", format,
            named_channels));
    if (compression.empty())
        return true;
    const std::string name = Strutil::lower(compression.substr(0, compression.find(':')));
    if (deep && !deep_compressions().count(name))
        return fail(Strutil::fmt::format("deep OpenEXR takes no compression '{}' (known: {})",
                                         compression, Strutil::join(deep_compressions(), ", ")));
    const auto known = compressions().find(format);
    if (known == compressions().end())
        return fail(Strutil::fmt::format("{} files take no compression ('{}' given)", format,
                                         compression));
    if (std::find(known->second.begin(), known->second.end(), name) == known->second.end())
        return fail(Strutil::fmt::format("unknown {} compression '{}' (known: {})", format,
                                         compression, Strutil::join(known->second, ", ")));
    return true;
}

namespace {

/// An IOFile that keeps the system's reason for its first failed write:
/// OpenEXR turns a short write into an exception whose message OpenImageIO
/// does not pass on.
class ReportingFile : public Filesystem::IOFile {
public:
    using IOFile::IOFile;
    size_t write(const void* buf, size_t size) override
    {
        return noted(IOFile::write(buf, size), size);
    }
    size_t pwrite(const void* buf, size_t size, int64_t offset) override
    {
        return noted(IOFile::pwrite(buf, size, offset), size);
    }
    const std::string& why() const { return m_why; }

private:
    size_t noted(size_t written, size_t size)
    {
        if (written < size && m_why.empty())
            m_why = std::strerror(errno ? errno : EIO);
        return written;
    }
    std::string m_why;
};

/// Why writing `filename` failed, where a writer that names files does not
/// say: its disk is full, or the process's file size limit was reached
/// ("" when neither).
std::string write_limit(const std::string& filename)
{
    const std::string folder = Filesystem::parent_path(filename);
    struct statvfs disk;
    if (::statvfs(folder.empty() ? "." : folder.c_str(), &disk) == 0
        && uint64_t(disk.f_bavail) * disk.f_frsize < (uint64_t(1) << 20))
        return std::strerror(ENOSPC);
    struct rlimit size;
    if (::getrlimit(RLIMIT_FSIZE, &size) == 0 && size.rlim_cur != RLIM_INFINITY)
        return Strutil::fmt::format("{} (the process's file size limit is {} KB)",
                                    std::strerror(EFBIG), size.rlim_cur / 1024);
    return "";
}

/// Rows of a deep image written at a time: OpenImageIO builds a pointer
/// per pixel and channel for what it writes, 8 bytes against a sample's
/// 16, so a whole 4K frame took 0.5 GB of them and twice the time.
constexpr int deep_band_rows = 16;

/// Copies the samples of pixels [begin, end) of `from` into `band`.
void copy_band(const DeepData& from, int64_t begin, int64_t end, DeepData& band,
               std::vector<unsigned int>& counts)
{
    counts.resize(size_t(end - begin));
    size_t samples = 0;
    int64_t first = -1, last = -1;
    for (int64_t p = begin; p < end; ++p) {
        counts[size_t(p - begin)] = unsigned(from.samples(p));
        samples += counts[size_t(p - begin)];
        if (counts[size_t(p - begin)]) {
            first = first < 0 ? p : first;
            last = p;
        }
    }
    band.set_all_samples(counts);
    if (samples == 0)
        return;
    // A pixel's samples follow the previous pixel's, unless some pixel holds
    // room for more than it has: then they are copied pixel by pixel.
    const size_t bytes = samples * from.samplesize();
    const char* start = static_cast<const char*>(from.data_ptr(first, 0, 0));
    const char* stop = static_cast<const char*>(from.data_ptr(last, 0, 0))
                       + counts[size_t(last - begin)] * from.samplesize();
    if (size_t(stop - start) == bytes) {
        std::memcpy(band.data_ptr(first - begin, 0, 0), start, bytes);
        return;
    }
    for (int64_t p = first; p <= last; ++p)
        if (counts[size_t(p - begin)])
            band.copy_deep_pixel(p - begin, from, p);
}

/// Writes a deep scanline image to an opened `out`, a band of rows at a
/// time; the file is the same as ImageBuf::write() makes.
bool write_deep_in_bands(ImageOutput& out, const ImageBuf& image)
{
    const ImageSpec& spec = image.spec();
    const DeepData& deep = *image.deepdata();
    std::vector<TypeDesc> types = spec.channelformats;
    types.resize(size_t(spec.nchannels), spec.format);
    DeepData band;
    std::vector<unsigned int> counts;
    for (int y = spec.y; y < spec.y + spec.height; y += deep_band_rows) {
        const int end = std::min(y + deep_band_rows, spec.y + spec.height);
        band.init(int64_t(end - y) * spec.width, spec.nchannels, types, spec.channelnames);
        copy_band(deep, int64_t(y - spec.y) * spec.width, int64_t(end - spec.y) * spec.width,
                  band, counts);
        if (!out.write_deep_scanlines(y, end, spec.z, band))
            return false;
    }
    return true;
}

}  // namespace

bool write_atomic(const std::string& filename,
                  const std::function<bool(ImageOutput&, const std::string&)>& write,
                  std::string& error)
{
    auto out = ImageOutput::create(filename);
    if (!out) {
        const std::string why = OIIO::geterror();  // geterror() clears it: read once
        error = Strutil::fmt::format("{}: {}", filename,
                                     why.empty() ? "no format writes this file type" : why);
        return false;
    }
    // OpenEXR writes into the file created for it. OpenImageIO's other
    // writers do not report a failed write (on a full disk PNG left a
    // truncated file and said nothing, and libjpeg ended the process), so
    // those that take an IOProxy encode in memory, written here with every
    // write checked. TIFF (whose IOProxy output OpenImageIO 2.4 writes
    // without its image length) and the writers without one write by name,
    // in a folder of their own; TIFF reports a failed write, the others'
    // files are read back whole.
    const std::string format = out->format_name();
    const bool by_name = format == "tiff" || !out->supports("ioproxy");
    TemporaryFile temporary(filename, by_name ? TemporaryFile::Kind::InFolder
                                              : TemporaryFile::Kind::File);
    if (!temporary.created()) {
        error = temporary.creation_error();
        return false;
    }
    const std::string& tmp = temporary.path();
    // Errors name the user's file, never the temporary one.
    auto fail = [&](const std::string& why) {
        error = Strutil::fmt::format(
            "{}: {}", filename,
            Strutil::replace(Strutil::replace(why, tmp, filename, true), "\n", " ", true));
        return false;
    };
    // The system's reason first: writers say "Could not open" or nothing.
    auto written = [&](const ReportingFile* file = nullptr) {
        if (write(*out, tmp) && out->close())
            return true;
        const std::string said = out->geterror(), system = file ? file->why() : "",
                          reason = !system.empty() ? system : write_limit(filename);
        if (reason.empty())
            return fail(said.empty() ? "cannot write" : said);
        return fail("cannot write: " + reason + (said.empty() ? "" : " (" + said + ")"));
    };
    std::string why;
    if (format == "openexr") {
        FILE* file = ::fdopen(::dup(temporary.descriptor()), "wb");
        if (!file)
            return fail("cannot write: " + std::string(std::strerror(errno)));
        bool ok = false;
        {
            ReportingFile io(file, Filesystem::IOProxy::Write);
            ok = out->set_ioproxy(&io) && written(&io);
            out.reset();
        }
        const bool flushed = std::fflush(file) == 0 && !std::ferror(file);
        const std::string flush_error = flushed ? "" : std::strerror(errno);
        std::fclose(file);
        if (!ok)
            return false;
        if (!flushed)
            return fail("cannot write: " + flush_error);
    } else if (!by_name) {
        Filesystem::IOVecOutput memory;
        if (!out->set_ioproxy(&memory) || !written())
            return false;
        out.reset();
        if (!temporary.write(memory.buffer().data(), memory.buffer().size(), why))
            return fail("cannot write: " + why);
    } else {
        if (!written())
            return false;
        out.reset();
        ImageBuf back;
        if (format != "tiff" && !read_image_file(tmp, "the file written", back, why)) {
            const std::string limit = write_limit(filename);
            return fail("cannot write: "
                        + (limit.empty() ? std::string("it does not read back complete") : limit));
        }
    }
    return temporary.commit(error);
}

bool write_text_atomic(const std::string& filename, const std::string& text,
                       std::string& error)
{
    TemporaryFile temporary(filename);
    std::string why;
    if (!temporary.created()) {
        error = temporary.creation_error();
        return false;
    }
    if (!temporary.write(text.data(), text.size(), why)) {
        error = filename + ": cannot write: " + why;
        return false;
    }
    return temporary.commit(error);
}

bool write_image_atomic(const ImageBuf& image, const std::string& filename,
                        TypeDesc type, const std::string& compression,
                        std::string& error, int float_channels, TypeDesc* written)
{
    ImageSpec spec = image.spec();
    if (type != TypeUnknown && !spec.deep) {
        spec.set_format(type);
        spec.channelformats.clear();
        if (float_channels > 0 && type != TypeFloat) {
            spec.channelformats.assign(spec.nchannels, type);
            std::fill(spec.channelformats.end() - std::min(float_channels, spec.nchannels),
                      spec.channelformats.end(), TypeFloat);
        }
    }
    if (!compression.empty())
        spec.attribute("compression", compression);
    return write_atomic(filename, [&](ImageOutput& out, const std::string& tmp) {
        // A format takes the nearest type it has (OpenEXR: half for 8 bits).
        auto open = [&](const ImageSpec& opened) {
            if (!out.open(tmp, opened))
                return false;
            if (written)
                *written = out.spec().format;
            return true;
        };
        if (out.supports("displaywindow")) {
            ImageBuf half;
            if (spec.format == TypeHalf && spec.channelformats.empty() && !spec.deep
                && convert_to_half(image, half))
                return open(spec) && half.write(&out);
            if (spec.deep && spec.tile_width == 0 && spec.depth == 1)
                return open(spec) && write_deep_in_bands(out, image);
            return open(spec) && image.write(&out);
        }
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
        return open(framed_spec) && framed.write(&out);
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
        spec.erase_attribute(depth_kind_attribute);  // Z is planar now
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
