// The shot for Python: NativeShot, its settings by name, its frames and
// camera, .dof files, and the file helpers the package's sequences use.
#pragma once

#include <optional>

#include <pybind11/pybind11.h>

#include <defocus/shot/shot.h>

namespace defocus_python {

namespace py = pybind11;

/// Adds NativeShot, load_shot, settings, frame_path, chunk_frames,
/// written_with_settings and write_text_atomic to `m`.
void bind_shot(py::module_& m);

/// The frame to render: the one given, else the shot's first.
int frame_or_first(const defocus::Shot& shot, std::optional<int> frame);

}  // namespace defocus_python
