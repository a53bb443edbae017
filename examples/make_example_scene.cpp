// Writes a small layered scene as a multi-part EXR, the kind of file
// `defocus` reads: one part per layer, each premultiplied RGBA (half) and
// Z (float, metres), each with its own data window, with overscan.
//
//   make_example_scene OUTPUT.exr [--width W] [--height H]
#include <cmath>
#include <functional>
#include <cstdlib>
#include <string>
#include <vector>

#include <OpenImageIO/argparse.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

using namespace OIIO;

namespace {

struct Sample {
    float r, g, b, a, z;
};

/// One layer: a name, a data window and a function giving each pixel in
/// normalised display coordinates (u, v in [0, 1] across the display).
struct LayerRecipe {
    const char* name;
    ROI window;
    std::function<Sample(double u, double v)> shade;
};

double cell_noise(int i)
{
    unsigned h = unsigned(i) * 2654435761u;
    h ^= h >> 15;
    h *= 2246822519u;
    return double(h >> 8) / double(1u << 24);
}

ImageSpec part_spec(const LayerRecipe& layer, int width, int height)
{
    ImageSpec spec(layer.window.width(), layer.window.height(), 5, TypeHalf);
    spec.x = layer.window.xbegin;
    spec.y = layer.window.ybegin;
    spec.full_width  = width;
    spec.full_height = height;
    spec.channelnames  = { "R", "G", "B", "A", "Z" };
    spec.channelformats = { TypeHalf, TypeHalf, TypeHalf, TypeHalf, TypeFloat };
    spec.alpha_channel = 3;
    spec.z_channel = 4;
    spec.attribute("name", layer.name);
    spec.attribute("compression", "zip");
    spec.attribute("defocus:exampleCamera",
                   "--focal 50 --fstop 1.8 --focus 4 --sensor 36");
    return spec;
}

}  // namespace

int main(int argc, const char* argv[])
{
    std::string output;
    int width = 1280, height = 720;
    ArgParse ap;
    ap.intro("make_example_scene -- writes a layered multi-part EXR scene")
        .usage("make_example_scene OUTPUT.exr [--width W] [--height H]");
    ap.arg("filename").hidden().action([&](cspan<const char*> a) { output = a[0]; });
    ap.arg("--width W").help("Display width (default: 1280)").action(
        [&](cspan<const char*> a) { width = Strutil::stoi(a[1]); });
    ap.arg("--height H").help("Display height (default: 720)").action(
        [&](cspan<const char*> a) { height = Strutil::stoi(a[1]); });
    if (ap.parse_args(argc, argv) < 0 || output.empty() || width < 16 || height < 16) {
        Strutil::print(stderr, "make_example_scene: {}\n",
                       ap.has_error() ? ap.geterror() : "usage: make_example_scene OUTPUT.exr");
        return EXIT_FAILURE;
    }
    if (ap.aborted())
        return EXIT_SUCCESS;

    const int over = width / 20;  // overscan on every side
    const double aspect = double(height) / width;
    const std::vector<LayerRecipe> layers = {
        { "sky", ROI(-over, width + over, -over, height + over),
          [&](double u, double v) -> Sample {
              // A dusk gradient with a field of bright lights: bokeh shows
              // on highlights.
              const int cell = int(u * 40) + 97 * int(v * 40);
              const double du = u * 40 - std::floor(u * 40) - 0.5;
              const double dv = v * 40 - std::floor(v * 40) - 0.5;
              const bool light = cell_noise(cell) < 0.08 && du * du + dv * dv < 0.02;
              const float l = light ? 20.0f : 0.0f;
              return { float(0.05 + 0.1 * v) + l, float(0.07 + 0.1 * v) + l * 0.8f,
                       float(0.25 - 0.1 * v) + l * 0.5f, 1.0f, 60.0f };
          } },
        { "hills", ROI(-over, width + over, height / 3, height + over),
          [&](double u, double v) -> Sample {
              const double ridge = 0.45 + 0.08 * std::sin(u * 7.0) + 0.04 * std::sin(u * 23.0);
              if (v / aspect < ridge)
                  return { 0, 0, 0, 0, 0 };
              // Depth falls from 25 m at the ridge to 6 m at the bottom:
              // a layer that is not planar.
              const double t = (v / aspect - ridge) / (1.0 - ridge);
              const float stripes = 0.5f + 0.5f * float(std::sin(u * 120.0 + t * 30.0) > 0);
              return { 0.08f * stripes, 0.25f * stripes, 0.06f, 1.0f,
                       float(25.0 - 19.0 * std::min(1.0, t)) };
          } },
        { "post", ROI(width * 11 / 20, width * 13 / 20, -over, height + over),
          [&](double u, double v) -> Sample {
              const double x = (u - 0.6) * 20.0;  // -1..1 across the post
              if (std::abs(x) > 0.8)
                  return { 0, 0, 0, 0, 0 };
              const float ring = (int(v / aspect * 12) % 2) ? 0.9f : 0.6f;
              return { ring, ring * 0.9f, ring * 0.8f, 1.0f, 4.0f };
          } },
        { "leaves", ROI(-over, width / 3, height / 2, height + over),
          [&](double u, double v) -> Sample {
              const double cu = u * 9.0, cv = v / aspect * 9.0;
              const int cell = int(std::floor(cu)) * 31 + int(std::floor(cv));
              const double du = cu - std::floor(cu) - 0.5, dv = cv - std::floor(cv) - 0.5;
              if (cell_noise(cell) < 0.35 || du * du + dv * dv > 0.2)
                  return { 0, 0, 0, 0, 0 };
              return { 0.05f, 0.35f, 0.08f, 1.0f, float(1.0 + 0.2 * cell_noise(cell + 7)) };
          } },
    };

    std::vector<ImageSpec> specs;
    for (const LayerRecipe& layer : layers)
        specs.push_back(part_spec(layer, width, height));
    auto out = ImageOutput::create(output);
    if (!out || !out->supports("multiimage")
        || !out->open(output, int(specs.size()), specs.data())) {
        Strutil::print(stderr, "make_example_scene: {}: {}\n", output,
                       out ? out->geterror() : "cannot write multi-part files of this type");
        return EXIT_FAILURE;
    }
    for (size_t i = 0; i < layers.size(); ++i) {
        const LayerRecipe& layer = layers[i];
        if (i > 0 && !out->open(output, specs[i], ImageOutput::AppendSubimage))
            break;
        std::vector<float> pixels;
        pixels.reserve(size_t(layer.window.width()) * layer.window.height() * 5);
        for (int y = layer.window.ybegin; y < layer.window.yend; ++y)
            for (int x = layer.window.xbegin; x < layer.window.xend; ++x) {
                const Sample s = layer.shade((x + 0.5) / width, (y + 0.5) / width);
                pixels.insert(pixels.end(), { s.r * s.a, s.g * s.a, s.b * s.a, s.a, s.z });
            }
        if (!out->write_image(TypeFloat, pixels.data()))
            break;
    }
    if (out->has_error() || !out->close()) {
        Strutil::print(stderr, "make_example_scene: {}: {}\n", output, out->geterror());
        return EXIT_FAILURE;
    }
    Strutil::print("wrote {} ({}x{}, {} layers)\n", output, width, height, layers.size());
    return EXIT_SUCCESS;
}
