#include "shot_binding.h"

#include <pybind11/stl.h>

#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>
#include <defocus/io/settings_hash.h>
#include <defocus/io/shot_file.h>
#include <defocus/render_frame.h>

#include "python_errors.h"

namespace defocus_python {

using namespace defocus;

int frame_or_first(const Shot& shot, std::optional<int> frame)
{
    if (frame)
        return *frame;
    std::vector<int> frames;
    std::string error;
    check(shot_frames(shot, frames, error), error);
    return frames.front();
}

namespace {

/// The camera values `frame` of a shot renders with (frame_camera), by
/// their Python names: camera_from_file's header values included, the
/// keyframes taken at the frame.
py::dict resolved_camera(const Shot& shot, std::optional<int> frame)
{
    const int at = frame_or_first(shot, frame);
    Camera camera;
    CameraOrigins origins;
    std::string error;
    bool found;
    {
        py::gil_scoped_release release;
        found = frame_camera(shot, at, camera, origins, error);
    }
    check(found, error);
    auto pixel = [](const std::optional<Imath::V2d>& p) -> py::object {
        return p ? py::object(py::make_tuple(p->x, p->y)) : py::none();
    };
    py::dict values;
    values["focal"]          = camera.focal_length_mm;
    values["fstop"]          = camera.fstop;
    values["focus"]          = camera.focus_distance;
    values["sensor"]         = camera.sensor_width_mm;
    values["focus_at"]       = pixel(camera.focus_pixel);
    values["focus_tilt"]     = py::make_tuple(camera.tilt_deg[0], camera.tilt_deg[1]);
    values["optical_centre"] = pixel(camera.axis_pixel);
    return values;
}

}  // namespace

void bind_shot(py::module_& m)
{
    py::class_<Shot>(m, "NativeShot")
        .def(py::init<>())
        .def(py::init<const Shot&>())
        .def_readwrite("inputs", &Shot::inputs)
        .def("get", [](const Shot& shot, const std::string& name) {
            return shot_setting(shot, name);
        })
        .def("set", [](Shot& shot, const std::string& name, const std::string& value,
                       const std::string& label) {
            std::string error;
            check(set_shot_setting(shot, name, value, error, label), error);
        })
        .def("is_given", [](const Shot& shot, const std::string& name) {
            return is_given(shot, name);
        })
        .def("check", [](const Shot& shot) {
            std::string error;
            check(check_shot(shot, error), error);
        })
        .def("frames", [](const Shot& shot) {
            std::vector<int> frames;
            std::string error;
            check(shot_frames(shot, frames, error), error);
            return frames;
        })
        .def("fits", [](const Shot& shot, int frame) {
            std::string error;
            check(frame_fits(shot, frame, error), error);
        })
        .def("resolved_camera", &resolved_camera)
        .def("settings_hash", [](const Shot& shot, int frame) {
            return settings_hash(shot, frame);
        })
        .def("to_json", [](const Shot& shot, const std::string& directory) {
            return shot_to_json(shot, directory);
        })
        .def("save", [](const Shot& shot, const std::string& path) {
            std::string error;
            check(save_shot(shot, path, error), error);
        });
    m.def("load_shot", [](const std::string& path) {
        Shot shot;
        std::string error;
        check(load_shot(path, shot, error), error);
        return shot;
    });
    m.def("settings", [] {
        std::vector<py::tuple> list;
        for (const ShotSetting& s : shot_settings())
            list.push_back(py::make_tuple(s.name, s.section, s.key, int(s.kind)));
        return list;
    });
    m.def("frame_path", &frame_path);
    m.def("chunk_frames", &chunk_frames);
    m.def("written_with_settings", [](const std::string& path, const std::string& hash) {
        std::string why;
        const bool current = written_with_settings(path, hash, why);
        return py::make_tuple(current, why);
    });
    m.def("write_text_atomic", [](const std::string& path, const std::string& text) {
        std::string error;
        check(write_text_atomic(path, text, error), error);
    });
}

}  // namespace defocus_python
