// The circle of confusion.
#include <catch2/catch.hpp>

#include <cmath>

#include <defocus/shot/camera.h>

using namespace defocus;

TEST_CASE("thin-lens CoC matches the garden camera")
{
    Camera cam;
    cam.focal_length_mm = 85;
    cam.fstop = 1.4;
    cam.focus_distance = 3.0;
    cam.sensor_width_mm = 36;
    const CircleOfConfusion coc(cam, 960);
    // c = f^2 / (N s) * W * (1/z_f - 1/z) with f = 0.085 m, s = 0.036 m.
    const double k = 0.085 * 0.085 / (1.4 * 0.036) * 960;
    CHECK(coc.diameter(3.0) == Approx(0.0).margin(1e-12));
    CHECK(coc.diameter(12.0) == Approx(k * (1 / 3.0 - 1 / 12.0)));
    CHECK(coc.diameter(1.0) == Approx(k * (1 / 3.0 - 1.0)));
    CHECK(coc.diameter(1.0) < 0);  // in front of the focus plane
    CHECK(coc.diameter(INFINITY) == Approx(k / 3.0));
    CHECK(coc.radius(1.0) == Approx(0.5 * k * (1.0 - 1 / 3.0)));
}

TEST_CASE("optical lens follows Potmesil and Chakravarty")
{
    Camera cam;
    cam.focal_length_mm = 50;
    cam.fstop = 2;
    cam.focus_distance = 2.0;
    cam.sensor_width_mm = 24;
    cam.lens = LensModel::Optical;
    const CircleOfConfusion coc(cam, 2048);
    const double f = 0.05, z = 5.0, zf = 2.0;
    const double expected = f * f * std::abs(z - zf) / (2 * z * (zf - f)) * 2048 / 0.024;
    CHECK(coc.diameter(z) == Approx(expected));
    CHECK(coc.diameter(1.0) < 0);
}

TEST_CASE("max blur clamps the CoC")
{
    Camera cam;
    cam.focus_distance = 2.0;
    cam.max_blur_px = 10;
    const CircleOfConfusion coc(cam, 1920);
    CHECK(coc.diameter(0.01) == -10);
    CHECK(coc.radius(0.01) == 5);
}

TEST_CASE("invalid cameras are named")
{
    Camera cam;
    std::string error;
    CHECK(check_camera(cam, error));
    cam.fstop = 0;
    CHECK_FALSE(check_camera(cam, error));
    CHECK_THAT(error, Catch::Contains("f-stop"));
    cam = Camera();
    cam.lens = LensModel::Optical;
    cam.focus_distance = 0.01;  // inside the 50 mm focal length
    CHECK_FALSE(check_camera(cam, error));
    CHECK_THAT(error, Catch::Contains("optical"));
}
