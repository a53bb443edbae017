#include <defocus/color/color.h>

#include <dlfcn.h>
#include <link.h>

#include <cstdlib>
#include <filesystem>

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/color.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/sysutil.h>

#include <defocus/color/primaries.h>
#include <defocus/shot/setting_words.h>

namespace OCIO = OCIO_NAMESPACE;

namespace defocus {

using namespace OIIO;
using Strutil::fmt::format;

namespace {

/// The file this code was loaded from, links resolved: the OpenImageIO
/// plugin, the Python module or a shared library (the file the loader
/// opened), or else the program that links the library statically. The
/// loader names a program as it was started (argv[0]: "defocus" when found
/// through PATH, or a symbolic link), so the program is /proc/self/exe.
std::string this_module_path()
{
    Dl_info info {};
    struct link_map* map = nullptr;
    std::string path = "/proc/self/exe";
    if (dladdr1(reinterpret_cast<const void*>(&this_module_path), &info,
                reinterpret_cast<void**>(&map), RTLD_DL_LINKMAP)
        && map && map->l_name && map->l_name[0])  // the program's is ""
        path = map->l_name;
    std::error_code ec;
    const std::filesystem::path resolved = std::filesystem::canonical(path, ec);
    return ec ? Sysutil::this_program_path() : resolved.string();
}

/// The shipped config in share/defocus of the nearest folder above this
/// module that has one: the prefix, in the build tree as once installed.
/// Programs and the plugin sit one folder below it (bin/, lib/), the Python
/// module four (lib/python3/dist-packages/defocus/).
std::string shipped_config_beside_module()
{
    std::string folder = Filesystem::parent_path(this_module_path());
    for (int up = 0; up < 4 && !folder.empty(); ++up) {
        folder = Filesystem::parent_path(folder);
        const std::string config = folder + "/share/defocus/config.ocio";
        if (Filesystem::exists(config))
            return config;
    }
    return "";
}

/// Set by set_package_ocio_config(), before main: a function's static, so
/// that it exists before any other file's static initialisation uses it.
std::string& package_config()
{
    static std::string path;
    return path;
}

/// What $OCIO names, "" when it is unset or empty.
std::string ocio_variable()
{
    const char* env = std::getenv("OCIO");
    return env ? env : "";
}

}  // namespace

void set_package_ocio_config(const char* path)
{
    // pkg-config gives it from the .pc file's folder: .../lib/pkgconfig/../..
    package_config() = path ? std::filesystem::path(path).lexically_normal().string() : "";
}

struct ColorManagement::Impl {
    OCIO::ConstConfigRcPtr ocio;  ///< for queries
    OIIO::ColorConfig oiio;       ///< for ImageBufAlgo's conversions
};

ColorManagement::ColorManagement() = default;
ColorManagement::~ColorManagement() = default;
ColorManagement::ColorManagement(ColorManagement&&) noexcept = default;
ColorManagement& ColorManagement::operator=(ColorManagement&&) noexcept = default;

bool ColorManagement::chosen(const std::string& explicit_file)
{
    return !explicit_file.empty() || !ocio_variable().empty();
}

bool ColorManagement::load(const std::string& explicit_file, std::string& error)
{
    const std::string env = ocio_variable();
    if (!explicit_file.empty()) {
        m_path = explicit_file;
        m_origin = mention("colorconfig");
    } else if (!env.empty()) {
        m_path = env;
        m_origin = "$OCIO";
    } else {
        // Where the package a program was built against has it; else
        // beside the program, plugin or module (build tree or installed);
        // else where this library was to be installed.
        m_path   = package_config();
        m_origin = "shipped";
        if (m_path.empty())
            m_path = shipped_config_beside_module();
        if (m_path.empty())
            m_path = DEFOCUS_INSTALLED_OCIO_CONFIG;
    }
    auto fail = [&](const std::string& problem) {
        error = format("{}: colour config ({}) {}", m_path, m_origin, problem);
        if (m_origin == "$OCIO")
            error += " (unset OCIO to use the shipped config)";
        return false;
    };
    if (!Filesystem::exists(m_path))
        return fail("not found");
    auto impl = std::make_unique<Impl>();
    try {
        impl->ocio = OCIO::Config::CreateFromFile(m_path.c_str());
        impl->ocio->validate();
    } catch (const OCIO::Exception& e) {
        return fail("fails to load: " + Strutil::replace(e.what(), "\n", " ", true));
    }
    if (!impl->oiio.reset(m_path))
        return fail("fails to load: " + impl->oiio.geterror());
    m_impl = std::move(impl);
    return true;
}

Imath::V3d ColorManagement::luma() const
{
    if (!m_impl)
        return luma_weights(nullptr);
    double weights[3];
    m_impl->ocio->getDefaultLumaCoefs(weights);
    return Imath::V3d(weights[0], weights[1], weights[2]);
}

Imath::V3d luma_weights(const ColorManagement* config)
{
    return config ? config->luma() : Imath::V3d(0.2126, 0.7152, 0.0722);
}

std::string ColorManagement::find_space(const std::string& name) const
{
    if (!m_impl || name.empty())
        return "";
    OCIO::ConstColorSpaceRcPtr cs = m_impl->ocio->getColorSpace(name.c_str());
    return cs ? cs->getName() : "";
}

std::vector<std::string> ColorManagement::space_names() const
{
    std::vector<std::string> names;
    if (!m_impl)
        return names;
    for (int i = 0; i < m_impl->ocio->getNumColorSpaces(); ++i)
        names.emplace_back(m_impl->ocio->getColorSpaceNameByIndex(i));
    return names;
}

std::string ColorManagement::require_space(const std::string& name, std::string& error) const
{
    const std::string found = find_space(name);
    if (found.empty())
        error = format("unknown colour space '{}' (spaces: {})", name,
                       Strutil::join(space_names(), ", "));
    return found;
}

bool ColorManagement::is_data(const std::string& space) const
{
    OCIO::ConstColorSpaceRcPtr cs = m_impl ? m_impl->ocio->getColorSpace(space.c_str()) : nullptr;
    return cs && cs->isData();
}

bool ColorManagement::is_linear(const std::string& space) const
{
    if (!m_impl)
        return false;
    OCIO::ConstColorSpaceRcPtr cs = m_impl->ocio->getColorSpace(space.c_str());
    if (!cs || cs->isData())
        return false;
    const std::string encoding = cs->getEncoding();
    if (!encoding.empty())
        return encoding == "scene-linear" || encoding == "display-linear";
    return m_impl->oiio.isColorSpaceLinear(space);
}

std::string ColorManagement::scene_linear() const
{
    return find_space(OCIO::ROLE_SCENE_LINEAR);
}

std::string ColorManagement::default_display() const
{
    return m_impl ? m_impl->ocio->getDefaultDisplay() : "";
}

std::string ColorManagement::default_view(const std::string& display) const
{
    return m_impl ? m_impl->ocio->getDefaultView(display.c_str()) : "";
}

bool ColorManagement::check_display_view(const std::string& display, const std::string& view,
                                         std::string& error) const
{
    const OCIO::Config& c = *m_impl->ocio;
    std::vector<std::string> displays, views;
    for (int i = 0; i < c.getNumDisplays(); ++i)
        displays.emplace_back(c.getDisplay(i));
    if (std::find(displays.begin(), displays.end(), display) == displays.end()) {
        error = format("unknown display '{}' (displays: {})", display,
                       Strutil::join(displays, ", "));
        return false;
    }
    for (int i = 0; i < c.getNumViews(display.c_str()); ++i)
        views.emplace_back(c.getView(display.c_str(), i));
    if (std::find(views.begin(), views.end(), view) == views.end()) {
        error = format("unknown view '{}' of display '{}' (views: {})", view, display,
                       Strutil::join(views, ", "));
        return false;
    }
    return true;
}

namespace {

/// Conversions to or from an encoding that is not linear must see the
/// colour a surface has, not its colour times its coverage.
bool needs_unpremult(const ColorManagement& config, const std::string& from,
                     const std::string& to)
{
    return !(config.is_linear(from) && config.is_linear(to));
}

}  // namespace

bool ColorManagement::convert(ImageBuf& image, const std::string& from, const std::string& to,
                          std::string& error, int nthreads) const
{
    if (from == to)
        return true;
    ROI colour = image.roi();
    colour.chbegin = 0;
    colour.chend = std::min(3, image.nchannels());
    if (!ImageBufAlgo::colorconvert(image, image, from, to, needs_unpremult(*this, from, to),
                                    "", "", &m_impl->oiio, colour, nthreads)) {
        error = format("colour conversion {} -> {}: {}", from, to, image.geterror());
        return false;
    }
    return true;
}

bool ColorManagement::convert(DeepImage& image, const std::string& from, const std::string& to,
                          std::string& error, int nthreads) const
{
    if (from == to)
        return true;
    ColorProcessorHandle processor = m_impl->oiio.createColorProcessor(from, to);
    if (!processor) {
        error = format("colour conversion {} -> {}: {}", from, to, m_impl->oiio.geterror());
        return false;
    }
    const bool unpremult = needs_unpremult(*this, from, to);
    parallel_for(int64_t(0), int64_t(image.samples.size()), [&](int64_t i) {
        DeepSample& s = image.samples[i];
        float rgba[4] = { s.r, s.g, s.b, s.a };
        ImageBufAlgo::colorconvert(span<float>(rgba, 4), processor.get(), unpremult);
        s.r = rgba[0], s.g = rgba[1], s.b = rgba[2];
    }, paropt(nthreads));
    return true;
}

bool ColorManagement::display(ImageBuf& dst, const ImageBuf& src, const std::string& from,
                          const std::string& display, const std::string& view,
                          std::string& error, int nthreads) const
{
    if (!check_display_view(display, view, error))
        return false;
    if (!ImageBufAlgo::ociodisplay(dst, src, display, view, from, "", true, "", "",
                                   &m_impl->oiio, {}, nthreads)) {
        error = format("display {} / {}: {}", display, view, dst.geterror());
        return false;
    }
    // The pixels are now the view's encoding, not the space of `src`,
    // whose tags they were given.
    const std::string encoding
        = m_impl->ocio->getDisplayViewColorSpaceName(display.c_str(), view.c_str());
    dst.specmod().attribute("oiio:ColorSpace", encoding);
    record_color_space(dst.specmod(), *this, encoding);
    return true;
}

bool convert_scene(Scene& scene, const ColorManagement& config, const std::string& from,
                   const std::string& to, std::string& error, int nthreads)
{
    return for_each_content(scene,
        [&](Layer& layer) { return config.convert(layer.color, from, to, error, nthreads); },
        [&](DeepImage& image) { return config.convert(image, from, to, error, nthreads); });
}

}  // namespace defocus
