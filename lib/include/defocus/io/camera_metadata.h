// The camera a render recorded in its file's header, and where each of a
// frame's camera values came from.
#pragma once

#include <string>

#include <OpenImageIO/imageio.h>

namespace defocus {

/// One camera value found in a header: the value in defocus's units
/// (metres, mm, f-number) and the attribute it was read from; an empty
/// attribute when the header has none.
struct HeaderValue {
    double value = 0.0;
    std::string attribute;
    bool found() const { return !attribute.empty(); }
};

/// The camera values of a header. Each is looked up in a table of the
/// attributes renderers write (the manual's Inputs page lists it):
/// OpenEXR's standard `focus` and `aperture`, Unreal Movie Render Queue's
/// `unreal/camera/...`, Arnold's `CameraFocalLength` and `CameraFilmApertureHorizontal`,
/// V-Ray's `cameraFocalLength` and `cameraAperture`. Values that are not
/// finite and positive are ignored.
struct HeaderCamera {
    HeaderValue focus_distance, fstop, focal_length_mm, sensor_width_mm;
    /// The focal length over the filmback width, from OpenEXR's
    /// worldToCamera and worldToNDC matrices (a perspective camera's
    /// projection): with a focal length, it gives the filmback.
    HeaderValue focal_over_filmback;
};

HeaderCamera camera_from_header(const OIIO::ImageSpec& spec);

/// The width of a pixel over its height that the header records
/// (OpenEXR's pixelAspectRatio; 1 when it records none, or nonsense).
double header_pixel_aspect(const OIIO::ImageSpec& spec);

/// Where each camera value of a frame came from, for -v: the option or
/// .dof key that set it, "file: ATTRIBUTE", "--focus-at X,Y" or "default".
struct CameraOrigins {
    std::string focal_length, fstop, focus, sensor_width;
};

}  // namespace defocus
