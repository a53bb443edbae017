// Colour management with OpenColorIO: spreading adds light, so it is only
// right in linear light. Inputs are converted to the config's scene_linear
// space before slicing and spreading; the result is converted to the space
// the user asks for.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Imath/ImathVec.h>
#include <OpenImageIO/imagebuf.h>

#include <defocus/scene.h>

namespace defocus {

/// Where the installed package's shipped config is, for a program that
/// links the library statically and lives elsewhere (it cannot find the
/// config beside itself). Such programs call it before main through this
/// header: the installed CMake package defines DEFOCUS_PACKAGE_OCIO_CONFIG
/// for them, from where it is installed (any prefix); with pkg-config,
/// define it from `pkg-config --variable=ocio_config defocus`.
void set_package_ocio_config(const char* path);

#ifdef DEFOCUS_PACKAGE_OCIO_CONFIG
namespace package_detail {
inline const bool ocio_config_set = (set_package_ocio_config(DEFOCUS_PACKAGE_OCIO_CONFIG), true);
}
#endif

/// A loaded OpenColorIO config.
class ColorManagement {
public:
    ColorManagement();
    ~ColorManagement();
    ColorManagement(ColorManagement&&) noexcept;
    ColorManagement& operator=(ColorManagement&&) noexcept;

    /// Loads the first of: `explicit_file` (when not empty), $OCIO, the
    /// config shipped with defocus: where the installed package a program
    /// was built against has it (set_package_ocio_config), else relative to
    /// the program, plugin or Python module the library is part of, links
    /// resolved (share/defocus/config.ocio in the nearest of the four
    /// folders above it: the prefix, in the build tree and installed), else
    /// where this library was configured to install it.
    /// False with `error` saying which file failed and why.
    bool load(const std::string& explicit_file, std::string& error);

    /// Whether the user chose the config that load() takes (the argument
    /// or $OCIO) rather than leaving it to the shipped one.
    static bool chosen(const std::string& explicit_file);

    /// The file loaded, and how it was chosen ("--colorconfig", "$OCIO",
    /// "shipped").
    const std::string& path() const { return m_path; }
    const std::string& origin() const { return m_origin; }

    /// The canonical name of a colour space, role or alias, or "" when the
    /// config has none of that name.
    std::string find_space(const std::string& name) const;
    /// find_space(), or "" with `error` listing the config's spaces.
    std::string require_space(const std::string& name, std::string& error) const;
    std::vector<std::string> space_names() const;

    bool is_data(const std::string& space) const;
    /// True for spaces whose encoding is linear light: converting between
    /// two of them is a 3x3 matrix, which commutes with spreading.
    bool is_linear(const std::string& space) const;
    std::string scene_linear() const;
    /// The weights of R, G and B in luminance, for the config's
    /// scene_linear space (its `luma` entry; unloaded: luma_weights()).
    Imath::V3d luma() const;

    std::string default_display() const;
    std::string default_view(const std::string& display) const;
    /// True when the display has the view; else false with `error`
    /// listing the displays or the display's views.
    bool check_display_view(const std::string& display, const std::string& view,
                            std::string& error) const;

    /// Converts the colour channels (R,G,B) of premultiplied RGBA `image`
    /// from one space to another in place. Conversions involving a space
    /// that is not linear work on un-premultiplied colour. Alpha and any
    /// other channel are never touched.
    bool convert(OIIO::ImageBuf& image, const std::string& from, const std::string& to,
                 std::string& error, int nthreads = 0) const;
    /// The same for every sample of a deep image.
    bool convert(DeepImage& image, const std::string& from, const std::string& to,
                 std::string& error, int nthreads = 0) const;

    /// A display-referred image of premultiplied RGBA `src` (in `from`)
    /// through `display` and `view`, for a preview.
    bool display(OIIO::ImageBuf& dst, const OIIO::ImageBuf& src, const std::string& from,
                 const std::string& display, const std::string& view,
                 std::string& error, int nthreads = 0) const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
    std::string m_path, m_origin;
};

/// The luminance weights of `config`, or without one (null) those of
/// linear Rec.709 (ITU-R BT.709), as which an input is then taken.
Imath::V3d luma_weights(const ColorManagement* config);

/// Converts every layer, flat render and deep image of a scene from
/// `from` to `to` (see ColorManagement::convert).
bool convert_scene(Scene& scene, const ColorManagement& config, const std::string& from,
                   const std::string& to, std::string& error, int nthreads = 0);

}  // namespace defocus
