// Images and layers between numpy arrays and OpenImageIO's ImageBuf, placed
// at the windows the Python side gives.
#pragma once

#include <string>
#include <tuple>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <OpenImageIO/imagebuf.h>

#include <defocus/scene.h>

namespace defocus_python {

namespace py = pybind11;

/// Where arrays lie: the data window's origin (x, y) and the display
/// window (x, y, width, height), as OpenImageIO's ImageSpec has them.
using Windows = std::tuple<int, int, int, int, int, int>;

/// Layers from Python: (name, RGBA, Z), checked there.
using ArrayLayers = std::vector<std::tuple<std::string, py::array_t<float, py::array::c_style>,
                                           py::array_t<float, py::array::c_style>>>;

/// The image's data window (or display window, zero outside the data) as
/// float32 rows of pixels, and its spec as OpenImageIO's XML.
py::tuple image_result(const OIIO::ImageBuf& image, bool crop);

/// A scene in memory, named `source` in messages. One render is flat and
/// is cut into layers, as the CLI cuts a file of one part; several are
/// layers given as such.
defocus::Scene array_scene(const ArrayLayers& layers, const Windows& windows,
                           const char* source);

/// Layers as (name, RGBA, Z) arrays over `window`.
std::vector<py::tuple> layer_arrays(const std::vector<defocus::Layer>& layers,
                                    const OIIO::ROI& window);

}  // namespace defocus_python
