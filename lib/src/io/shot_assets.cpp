#include <defocus/io/shot_assets.h>

#include <defocus/io/aperture_files.h>

namespace defocus {

bool read_shot_assets(const Shot& shot, ShotAssets& assets, std::string& error)
{
    assets = ShotAssets();
    auto color = std::make_shared<ColorManagement>();
    if (color->load(shot.color_config, assets.no_color)) {
        assets.color = std::move(color);
    } else if (color->chosen(shot.color_config) || !shot.input_space.empty()
               || !shot.output_space.empty()) {
        // Without a config the input is taken as linear, unless the user
        // chose a config or names a colour space: a config chosen and not
        // loaded would leave an sRGB image unmanaged by surprise.
        error = assets.no_color;
        return false;
    }
    return read_aperture_images(shot, luma_weights(assets.color.get()), assets.aperture, error);
}

}  // namespace defocus
