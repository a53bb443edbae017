#include <defocus/io/shot_assets.h>

#include <defocus/io/aperture_files.h>

namespace defocus {

bool read_shot_assets(const Shot& shot, ShotAssets& assets, std::string& error)
{
    assets = ShotAssets();
    auto color = std::make_shared<ColorManagement>();
    if (color->load(shot.color_config, assets.no_color)) {
        assets.color = std::move(color);
    } else if (!shot.color_config.empty() || !shot.input_space.empty()
               || !shot.output_space.empty()) {
        // Without a config the input is taken as linear, unless the shot
        // names a config or a colour space.
        error = assets.no_color;
        return false;
    }
    return read_aperture_images(shot, luma_weights(assets.color.get()), assets.aperture, error);
}

}  // namespace defocus
