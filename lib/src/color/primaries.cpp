#include <defocus/color/primaries.h>

#include <cmath>

#include <OpenImageIO/strutil.h>

namespace defocus {

namespace {

// Primaries and whites: ACES (SMPTE ST 2065-1, S-2014-004), ITU-R BT.709,
// SMPTE EG 432-1 (P3 with the D65 white), ITU-R BT.2020.
using Chromaticities = std::array<float, 8>;
constexpr Chromaticities ap0 = { 0.7347f, 0.2653f, 0.0f, 1.0f, 0.0001f, -0.077f, 0.32168f, 0.33767f };
constexpr Chromaticities ap1 = { 0.713f, 0.293f, 0.165f, 0.830f, 0.128f, 0.044f, 0.32168f, 0.33767f };
constexpr Chromaticities rec709 = { 0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f };
constexpr Chromaticities p3d65 = { 0.680f, 0.320f, 0.265f, 0.690f, 0.150f, 0.060f, 0.3127f, 0.3290f };
constexpr Chromaticities rec2020 = { 0.708f, 0.292f, 0.170f, 0.797f, 0.131f, 0.046f, 0.3127f, 0.3290f };

const KnownSpace known_spaces[] = {
    { "ACES AP0", "lin_ap0_scene", { "ACES2065-1", "lin_ap0", "lin_ap0_scene" }, ap0, true },
    { "ACES AP1", "lin_ap1_scene", { "ACEScg", "lin_ap1", "lin_ap1_scene" }, ap1, true },
    { "ACES AP1 with the ACEScct curve", "acescct_ap1_scene",
      { "ACEScct", "acescct_ap1", "acescct_ap1_scene" }, ap1, false },
    { "Rec.709", "lin_rec709_scene", { "Linear Rec.709 (sRGB)", "lin_rec709", "lin_rec709_scene" },
      rec709, true },
    { "Rec.709 with the sRGB curve", "srgb_rec709_scene",
      { "sRGB - Texture", "srgb_tx", "srgb_rec709_scene" }, rec709, false },
    { "P3-D65", "lin_p3d65_scene", { "Linear P3-D65", "lin_p3d65", "lin_p3d65_scene" }, p3d65, true },
    { "Rec.2020", "lin_rec2020_scene", { "Linear Rec.2020", "lin_rec2020", "lin_rec2020_scene" },
      rec2020, true },
};

}  // namespace

std::string config_space(const ColorManagement& config, const KnownSpace& known)
{
    for (const char* name : known.names) {
        const std::string found = config.find_space(name);
        if (!found.empty())
            return found;
    }
    return "";
}

const KnownSpace* known_space(const ColorManagement& config, const std::string& space)
{
    for (const KnownSpace& known : known_spaces)
        if (!space.empty() && config_space(config, known) == space)
            return &known;
    return nullptr;
}

const KnownSpace* linear_space_with_chromaticities(const float xy[8])
{
    for (const KnownSpace& known : known_spaces) {
        bool match = known.linear;
        for (int i = 0; i < 8 && match; ++i)
            match = std::abs(known.chromaticities[i] - xy[i]) <= 0.001f;
        if (match)
            return &known;
    }
    return nullptr;
}

const KnownSpace* space_with_interop_id(const std::string& id)
{
    for (const KnownSpace& known : known_spaces)
        if (OIIO::Strutil::iequals(id, known.interop_id))
            return &known;
    return nullptr;
}

void record_color_space(OIIO::ImageSpec& spec, const ColorManagement& config,
                        const std::string& space)
{
    const KnownSpace* known = known_space(config, space);
    if (!known) {
        spec.erase_attribute("chromaticities");
        spec.erase_attribute("colorInteropID");
        return;
    }
    spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8),
                   known->chromaticities.data());
    spec.attribute("colorInteropID", known->interop_id);
}

}  // namespace defocus
