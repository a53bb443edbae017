#include "arrays.h"

#include "python_errors.h"

namespace defocus_python {

using namespace defocus;
using OIIO::ImageBuf;
using OIIO::ImageSpec;
using OIIO::ROI;
using OIIO::TypeFloat;

namespace {

/// `spec` placed at the windows.
void place(ImageSpec& spec, const Windows& windows)
{
    std::tie(spec.x, spec.y, spec.full_x, spec.full_y, spec.full_width, spec.full_height) =
        windows;
}

/// An ImageBuf of `channels` float channels from C-contiguous float32
/// pixels (checked by the Python side), placed at the windows.
ImageBuf buffer(const py::array_t<float, py::array::c_style>& pixels,
                std::vector<std::string> names, const Windows& windows)
{
    const int height = int(pixels.shape(0)), width = int(pixels.shape(1));
    ImageSpec spec(width, height, int(names.size()), TypeFloat);
    place(spec, windows);
    spec.channelnames = std::move(names);
    if (spec.nchannels == 4)
        spec.alpha_channel = 3;
    else
        spec.z_channel = 0;
    ImageBuf buf(spec);
    buf.set_pixels(buf.roi(), TypeFloat, pixels.data());
    return buf;
}

}  // namespace

py::tuple image_result(const ImageBuf& image, bool crop)
{
    const ImageSpec& spec = image.spec();
    check(!spec.deep, "deep=True makes a deep image, which no array holds: write it with "
                      "render_to_file() or render_sequence()");
    ROI roi = image.roi();
    if (crop)
        roi = ROI(spec.full_x, spec.full_x + spec.full_width, spec.full_y,
                  spec.full_y + spec.full_height, 0, 1, 0, spec.nchannels);
    py::array_t<float> pixels({ roi.height(), roi.width(), roi.nchannels() });
    float* data = pixels.mutable_data();
    {
        py::gil_scoped_release release;
        image.get_pixels(roi, TypeFloat, data);
    }
    ImageSpec described = spec;
    described.x = roi.xbegin, described.y = roi.ybegin;
    described.width = roi.width(), described.height = roi.height();
    return py::make_tuple(pixels, described.to_xml());
}

Scene array_scene(const ArrayLayers& layers, const Windows& windows, const char* source)
{
    Scene scene;
    scene.source = source;
    const bool flat = layers.size() == 1;
    for (const auto& [name, rgba, z] : layers) {
        Layer layer { name, buffer(rgba, { "R", "G", "B", "A" }, windows),
                      buffer(z, { "Z" }, windows) };
        (flat ? scene.flat : scene.layers).push_back(std::move(layer));
    }
    const ImageSpec& first = (flat ? scene.flat : scene.layers).front().color.spec();
    scene.spec = ImageSpec(first.width, first.height, 5, TypeFloat);
    place(scene.spec, windows);
    scene.spec.channelnames = { "R", "G", "B", "A", "Z" };
    scene.spec.alpha_channel = 3;
    scene.spec.z_channel = 4;
    return scene;
}

std::vector<py::tuple> layer_arrays(const std::vector<Layer>& layers, const ROI& window)
{
    std::vector<py::tuple> out;
    for (const Layer& layer : layers) {
        py::array_t<float> rgba({ window.height(), window.width(), 4 });
        py::array_t<float> z({ window.height(), window.width() });
        ROI color = window, depth = window;
        color.chend = 4, depth.chend = 1;
        layer.color.get_pixels(color, TypeFloat, rgba.mutable_data());
        layer.depth.get_pixels(depth, TypeFloat, z.mutable_data());
        out.push_back(py::make_tuple(layer.name, rgba, z));
    }
    return out;
}

}  // namespace defocus_python
