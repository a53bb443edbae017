// An OpenImageIO format plugin: any OIIO program opens a .dof scene file as
// the defocused image it describes. open() reports the spec from the
// inputs' headers; the first read of pixels renders the frame through
// render_frame, as the defocus command's render service does (run_shot.h),
// and later reads reuse it.

#include <algorithm>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <defocus/error_line.h>
#include <defocus/io/file_stamps.h>
#include <defocus/io/frames.h>
#include <defocus/render_frame.h>
#include <defocus/shot/option_value.h>
#include <defocus/io/shot_file.h>

OIIO_PLUGIN_NAMESPACE_BEGIN

namespace {

using defocus::Shot;

/// How many .dof files this thread is opening or rendering, one inside
/// another: a .dof's inputs open through this plugin too. load_shot()
/// refuses cycles among the files a .dof names; this bounds what only
/// shows at run time (a frame pattern of .dof files), which would
/// otherwise recurse until the host's stack overflows.
thread_local int nesting = 0;

struct Nesting {
    Nesting() { ++nesting; }
    ~Nesting() { --nesting; }
    bool too_deep() const { return nesting > defocus::max_shot_file_nesting; }
};

class DofInput final : public ImageInput {
public:
    const char* format_name() const override { return "dof"; }
    bool valid_file(const std::string& filename) const override;
    bool open(const std::string& name, ImageSpec& newspec) override
    {
        return open(name, newspec, ImageSpec());
    }
    bool open(const std::string& name, ImageSpec& newspec, const ImageSpec& config) override;
    bool close() override;
    bool read_native_scanline(int subimage, int miplevel, int y, int z, void* data) override
    {
        return read_native_scanlines(subimage, miplevel, y, y + 1, z, data);
    }
    bool read_native_scanlines(int subimage, int miplevel, int ybegin, int yend, int z,
                               void* data) override;
    bool read_native_deep_scanlines(int subimage, int miplevel, int ybegin, int yend, int z,
                                    int chbegin, int chend, DeepData& deepdata) override;

private:
    bool check_rows(int subimage, int miplevel, int ybegin, int yend);
    bool apply_hints(const ImageSpec& config, bool& frame_given, std::string& error);
    bool render(std::string& error);
    bool render_once();

    std::string m_filename;
    Shot m_shot;
    defocus::ShotAssets m_assets;  ///< read once when the .dof is opened
    int m_frame = 1;
    std::mutex m_render_mutex;
    bool m_rendered = false;
    std::string m_render_error;
    /// The frame, in the spec's window and pixel type (deep, for a deep
    /// result).
    ImageBuf m_pixels;
    std::vector<defocus::FileStamp> m_inputs;  ///< the files the frame reads, as open() found them
};

/// A host that opens a sequence's .dof again without a frame (oiiotool
/// --frames 1-5 shot.dof -o out.#.exr) gets the first frame each time:
/// said once per file on stderr, the only channel a plugin has besides
/// errors.
void warn_if_reopened(const std::string& name, int frame)
{
    static std::mutex mutex;
    static std::map<std::string, int> opened;  // times opened without a frame
    std::lock_guard<std::mutex> lock(mutex);
    if (++opened[name] == 2)
        Strutil::print(stderr,
                       "defocus: warning: {} is a sequence opened again without a frame: each "
                       "open gives frame {}. Name the frame in the file name ({}), or give it "
                       "with --iconfig dof:frame {{FRAME_NUMBER}}\n",
                       name, frame,
                       name.substr(0, name.size() - 4) + ".#" + name.substr(name.size() - 4));
}

/// Copies the deep pixels of `src` into `dst` (deep, in a window that
/// holds src's): the pixels src does not cover keep no samples.
void copy_deep_pixels(ImageBuf& dst, const ImageBuf& src)
{
    const ROI roi = roi_intersection(dst.roi(), src.roi());
    DeepData& to = *dst.deepdata();
    const DeepData& from = *src.deepdata();
    // Sized first: DeepData moves every later pixel's samples each time
    // one pixel grows.
    std::vector<unsigned int> counts(static_cast<size_t>(to.pixels()), 0);
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x)
            counts[size_t(dst.pixelindex(x, y, 0))] = from.samples(src.pixelindex(x, y, 0));
    to.set_all_samples(counts);
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const int64_t p = dst.pixelindex(x, y, 0);
            if (counts[size_t(p)] > 0)
                std::memcpy(to.data_ptr(p, 0, 0), from.data_ptr(src.pixelindex(x, y, 0), 0, 0),
                            counts[size_t(p)] * from.samplesize());
        }
}

/// Rows [ybegin, yend) of channels [chbegin, chend) of `image` (a frame of
/// `spec`'s window), as a reader hands deep rows to its host.
void deep_rows(const DeepData& image, const ImageSpec& spec, int ybegin, int yend, int chbegin,
               int chend, DeepData& rows)
{
    std::vector<TypeDesc> types;
    std::vector<std::string> names;
    for (int c = chbegin; c < chend; ++c) {
        types.push_back(spec.channelformat(c));
        names.push_back(spec.channelnames[c]);
    }
    const int64_t first = int64_t(ybegin - spec.y) * spec.width;
    const int64_t npixels = int64_t(yend - ybegin) * spec.width;
    rows.init(npixels, chend - chbegin, types, names);
    std::vector<unsigned int> counts(static_cast<size_t>(npixels));
    for (int64_t p = 0; p < npixels; ++p)
        counts[size_t(p)] = unsigned(image.samples(first + p));
    rows.set_all_samples(counts);
    const bool whole = chbegin == 0 && chend == image.channels();
    for (int64_t p = 0; p < npixels; ++p) {
        const int samples = int(counts[size_t(p)]);
        if (samples == 0)
            continue;
        if (whole) {  // the same sample layout: copied as it is
            std::memcpy(rows.data_ptr(p, 0, 0), image.data_ptr(first + p, 0, 0),
                        size_t(samples) * image.samplesize());
        } else {
            for (int s = 0; s < samples; ++s)
                for (int c = chbegin; c < chend; ++c)
                    rows.set_deep_value(p, c - chbegin, s, image.deep_value(first + p, c, s));
        }
    }
}

bool DofInput::valid_file(const std::string& filename) const
{
    // No exception may leave a plugin entry point: it would end the host.
    try {
        Shot shot;
        std::string error, scene = filename;
        int frame = 0;
        defocus::numbered_file(filename, scene, frame);
        return Strutil::iends_with(filename, ".dof") && defocus::load_shot(scene, shot, error);
    } catch (const std::exception&) {
        return false;
    }
}

/// Configuration hints "dof:NAME" (or "dof:NAME_WITH_UNDERSCORES") override
/// the scene's settings of that name; "dof:frame" picks the frame.
bool DofInput::apply_hints(const ImageSpec& config, bool& frame_given, std::string& error)
{
    frame_given = false;
    for (const ParamValue& hint : config.extra_attribs) {
        std::string name = hint.name().string();
        if (!Strutil::istarts_with(name, "dof:"))
            continue;
        name = Strutil::replace(name.substr(4), "_", "-", true);
        const std::string value = hint.get_string();
        const std::string label = m_filename + ": dof:" + name;
        if (name == "frame") {
            frame_given = true;
            if (!defocus::parse_whole_number(label, value, -1e9, 1e9, m_frame, error))
                return false;
        } else if (!defocus::set_shot_setting(m_shot, name, value, error, label)) {
            return false;
        }
    }
    return true;
}

bool DofInput::open(const std::string& name, ImageSpec& newspec, const ImageSpec& config)
{
    close();
    m_filename = name;
    std::string error;
    auto fail = [&](const std::string& message) {
        errorfmt("{}", defocus::error_line(defocus::error_about(name, message),
                                           defocus::SettingForm::SceneFile));
        return false;
    };
    const Nesting nested;
    if (nested.too_deep())
        return fail(Strutil::fmt::format("scene files nested more than {} deep",
                                         defocus::max_shot_file_nesting));
    try {
        std::string scene = name;
        int numbered = 0;
        const bool frame_in_name = defocus::numbered_file(name, scene, numbered);
        if (!defocus::load_shot(scene, m_shot, error))
            return fail(error);
        bool frame_given = false;
        if (!apply_hints(config, frame_given, error))
            return fail(error);
        if (frame_in_name && !frame_given) {
            m_frame = numbered;
            frame_given = true;
        }
        if (!defocus::check_shot(m_shot, error)
            || !defocus::read_shot_assets(m_shot, m_assets, error))
            return fail(error);
        if (!frame_given) {
            std::vector<int> frames;
            if (!defocus::shot_frames(m_shot, frames, error))
                return fail(error);
            m_frame = frames.front();
            if (frames.size() > 1)
                warn_if_reopened(name, m_frame);
        }
        if (!defocus::frame_spec(m_shot, m_frame, m_assets, m_spec, error))
            return fail(error);
        m_inputs = defocus::stamp_files(defocus::files_read(m_shot, { m_frame }));
    } catch (const std::exception& e) {
        return fail(e.what());
    }
    newspec = m_spec;
    return true;
}

bool DofInput::close()
{
    std::lock_guard<std::mutex> lock(m_render_mutex);
    m_shot = Shot();
    m_assets = defocus::ShotAssets();
    m_frame = 1;
    m_rendered = false;
    m_render_error.clear();
    m_pixels.reset();
    m_inputs.clear();
    return true;
}

/// Renders the frame into m_pixels. False with `error` the problem.
bool DofInput::render(std::string& error)
{
    const Nesting nested;
    if (nested.too_deep()) {
        error = Strutil::fmt::format("{}: scene files nested more than {} deep", m_filename,
                                     defocus::max_shot_file_nesting);
        return false;
    }
    try {
        if (const std::string changed = defocus::first_changed(m_inputs); !changed.empty()) {
            error = Strutil::fmt::format("{}: {} changed since the scene was opened: open it "
                                         "again", m_filename, changed);
            return false;
        }
        defocus::FrameResult frame;
        if (!defocus::render_frame(m_shot, m_frame, m_assets, frame, error))
            return false;
        // In the spec's window and pixel type, as open() promised: where the
        // spec's window is larger (a grown window is the largest the blur
        // could make), the rest is zero.
        m_pixels.reset(m_spec);
        if (m_spec.deep) {
            copy_deep_pixels(m_pixels, frame.image);
            return true;
        }
        if (m_pixels.copy_pixels(frame.image))
            return true;
        error = m_pixels.geterror();
    } catch (const std::exception& e) {
        error = m_filename + ": " + e.what();
    }
    return false;
}

bool DofInput::render_once()
{
    std::lock_guard<std::mutex> lock(m_render_mutex);
    if (!m_rendered) {
        m_rendered = true;
        // The error is kept for every later read.
        if (!render(m_render_error) && m_render_error.empty())
            m_render_error = m_filename + ": cannot render";
    }
    if (!m_render_error.empty()) {
        errorfmt("{}", defocus::error_line(m_render_error, defocus::SettingForm::SceneFile));
        return false;
    }
    return true;
}

bool DofInput::check_rows(int subimage, int miplevel, int ybegin, int yend)
{
    if (subimage != 0 || miplevel != 0) {
        errorfmt("{}: a .dof scene has one image", m_filename);
        return false;
    }
    if (ybegin < m_spec.y || yend > m_spec.y + m_spec.height || ybegin >= yend) {
        errorfmt("{}: rows {} to {} are outside the image's rows {} to {}", m_filename, ybegin,
                 yend - 1, m_spec.y, m_spec.y + m_spec.height - 1);
        return false;
    }
    return render_once();
}

bool DofInput::read_native_scanlines(int subimage, int miplevel, int ybegin, int yend,
                                     int /*z*/, void* data)
{
    if (!check_rows(subimage, miplevel, ybegin, yend))
        return false;
    if (m_spec.deep) {
        errorfmt("{}: the scene's result is deep: read it as deep data", m_filename);
        return false;
    }
    const ROI rows(m_spec.x, m_spec.x + m_spec.width, ybegin, yend, 0, 1, 0, m_spec.nchannels);
    if (m_spec.channelformats.empty())
        return m_pixels.get_pixels(rows, m_spec.format, data);
    // Data channels are float beside colour of the output's type: each
    // channel goes to its place in the native pixel.
    const stride_t pixel = stride_t(m_spec.pixel_bytes(true));
    size_t offset = 0;
    for (int c = 0; c < m_spec.nchannels; ++c) {
        ROI one = rows;
        one.chbegin = c;
        one.chend = c + 1;
        if (!m_pixels.get_pixels(one, m_spec.channelformat(c), static_cast<char*>(data) + offset,
                                 pixel, pixel * m_spec.width))
            return false;
        offset += m_spec.channelformat(c).size();
    }
    return true;
}

bool DofInput::read_native_deep_scanlines(int subimage, int miplevel, int ybegin, int yend,
                                          int /*z*/, int chbegin, int chend, DeepData& deepdata)
{
    if (!check_rows(subimage, miplevel, ybegin, yend))
        return false;
    if (!m_spec.deep) {
        errorfmt("{}: the scene's result is not deep", m_filename);
        return false;
    }
    chend = std::clamp(chend, 0, m_spec.nchannels);
    chbegin = std::clamp(chbegin, 0, chend);
    deep_rows(*m_pixels.deepdata(), m_spec, ybegin, yend, chbegin, chend, deepdata);
    return true;
}

}  // namespace

OIIO_PLUGIN_EXPORTS_BEGIN

OIIO_EXPORT int dof_imageio_version = OIIO_PLUGIN_VERSION;

OIIO_EXPORT const char* dof_imageio_library_version()
{
    return "defocus " DEFOCUS_VERSION;
}

OIIO_EXPORT ImageInput* dof_input_imageio_create()
{
    return new DofInput;
}

OIIO_EXPORT const char* dof_input_extensions[] = { "dof", nullptr };

OIIO_PLUGIN_EXPORTS_END

OIIO_PLUGIN_NAMESPACE_END
