// Command-line options shared by defocus and layerize: the camera, the
// scene and its layering, threads; and strict parsing of their values.
#pragma once

#include <functional>
#include <string>

#include <OpenImageIO/argparse.h>

#include <defocus/camera.h>
#include <defocus/layering.h>
#include <defocus/scene_io.h>

namespace defocus {

/// Parses all of `text` as a finite number in [lo, hi] into `value`. On
/// failure sets `error` to a message naming `option` and returns false.
bool parse_number(const char* option, const std::string& text, double lo,
                  double hi, double& value, std::string& error);

/// An ArgParse action that stores an option's value into `into`.
std::function<void(OIIO::cspan<const char*>)> store_into(std::string& into);

/// The settings the shared options give.
struct SceneSettings {
    Camera camera;
    ReadOptions read;
    LayeringOptions layering;
    int threads = 0;
};

/// The shared options as typed, checked once ArgParse is done.
class SceneArguments {
public:
    /// Adds the "Camera:" options (--focal, --fstop, --focus, --sensor,
    /// --lens, --max-blur).
    void add_camera(OIIO::ArgParse& ap);
    /// Adds the "Scene:" options (--view, --layer, --layers).
    void add_scene(OIIO::ArgParse& ap);
    /// Adds --threads.
    void add_threads(OIIO::ArgParse& ap);

    /// Fills `settings`; false with `error` naming the first bad option.
    bool resolve(SceneSettings& settings, std::string& error) const;

private:
    std::string m_focal = "50", m_fstop = "2.8", m_focus, m_sensor = "36",
                m_lens = "thin", m_max_blur = "512", m_view, m_layer,
                m_layers = "0", m_threads = "0";
};

}  // namespace defocus
