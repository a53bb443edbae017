// Writes the two PSF images shipped in examples/psf/, for the hybrid
// method (defocus --psf-image): a disc with a bright rim, as many real
// lenses draw their bokeh, and a 7-blade iris.
//
//   make_psf_images OUTPUT_DIR
#include <cmath>
#include <cstdlib>
#include <functional>
#include <string>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/strutil.h>

using namespace OIIO;

namespace {

const int size = 64;
const double pi = 3.14159265358979323846;

/// An image of `shade` (x, y in [-1, 1]), averaged over 8x8 samples per
/// pixel so that the edges are antialiased.
bool write_psf(const std::string& path, const std::function<double(double, double)>& shade)
{
    ImageBuf image(ImageSpec(size, size, 1, TypeFloat));
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            double sum = 0.0;
            for (int j = 0; j < 8; ++j)
                for (int i = 0; i < 8; ++i)
                    sum += shade(2.0 * (x + (i + 0.5) / 8) / size - 1.0,
                                 2.0 * (y + (j + 0.5) / 8) / size - 1.0);
            const float v = float(sum / 64.0);
            image.setpixel(x, y, &v);
        }
    if (!image.write(path)) {
        Strutil::print(stderr, "make_psf_images: {}: {}\n", path, image.geterror());
        return false;
    }
    Strutil::print("wrote {}\n", path);
    return true;
}

}  // namespace

int main(int argc, const char* argv[])
{
    if (argc != 2) {
        Strutil::print(stderr, "usage: make_psf_images OUTPUT_DIR\n");
        return EXIT_FAILURE;
    }
    const std::string dir = argv[1];
    // A disc whose outer tenth is twice as bright as its inside.
    auto rim_disc = [](double x, double y) {
        const double r = std::hypot(x, y);
        return r > 1.0 ? 0.0 : r > 0.9 ? 2.0 : 1.0;
    };
    // A regular 7-gon with a vertex pointing up, of uniform brightness.
    auto iris = [](double x, double y) {
        const int n = 7;
        const double sector = 2.0 * pi / n;
        const double phi = std::atan2(-y, x) - pi / 2;
        const double local = std::fmod(phi + 8.0 * pi, sector) - 0.5 * sector;
        return std::hypot(x, y) * std::cos(local) <= std::cos(0.5 * sector) ? 1.0 : 0.0;
    };
    return write_psf(dir + "/disc_rim.exr", rim_disc) && write_psf(dir + "/blades7.exr", iris)
               ? EXIT_SUCCESS
               : EXIT_FAILURE;
}
