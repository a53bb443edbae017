// The circle of confusion.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>

#include <defocus/optics/camera.h>

using namespace defocus;
using OIIO::ROI;

TEST_CASE("thin-lens CoC matches the garden camera")
{
    Camera cam;
    cam.focal_length_mm = 85;
    cam.fstop = 1.4;
    cam.focus_distance = 3.0;
    cam.sensor_width_mm = 36;
    const CircleOfConfusion coc(cam, ROI(0, 960, 0, 540));
    // c = f^2 / (N s) * W * (1/z_f - 1/z) with f = 0.085 m, s = 0.036 m.
    const double k = 0.085 * 0.085 / (1.4 * 0.036) * 960;
    CHECK(coc.diameter(3.0, 0, 0) == Approx(0.0).margin(1e-12));
    CHECK(coc.diameter(12.0, 0, 0) == Approx(k * (1 / 3.0 - 1 / 12.0)));
    CHECK(coc.diameter(1.0, 0, 0) == Approx(k * (1 / 3.0 - 1.0)));
    CHECK(coc.diameter(1.0, 0, 0) < 0);  // in front of the focus plane
    CHECK(coc.diameter(INFINITY, 0, 0) == Approx(k / 3.0));
    CHECK(coc.radius(1.0, 0, 0) == Approx(0.5 * k * (1.0 - 1 / 3.0)));
}

TEST_CASE("optical lens follows Potmesil and Chakravarty")
{
    Camera cam;
    cam.focal_length_mm = 50;
    cam.fstop = 2;
    cam.focus_distance = 2.0;
    cam.sensor_width_mm = 24;
    cam.lens = LensModel::Optical;
    const CircleOfConfusion coc(cam, ROI(0, 2048, 0, 1080));
    const double f = 0.05, z = 5.0, zf = 2.0;
    const double expected = f * f * std::abs(z - zf) / (2 * z * (zf - f)) * 2048 / 0.024;
    CHECK(coc.diameter(z, 0, 0) == Approx(expected));
    CHECK(coc.diameter(1.0, 0, 0) < 0);
}

TEST_CASE("max blur clamps the CoC")
{
    Camera cam;
    cam.focus_distance = 2.0;
    cam.max_blur_px = 10;
    const CircleOfConfusion coc(cam, ROI(0, 1920, 0, 1080));
    CHECK(coc.diameter(0.01, 0, 0) == -10);
    CHECK(coc.radius(0.01, 0, 0) == 5);
}

TEST_CASE("invalid cameras are named")
{
    const ROI frame(0, 960, 0, 540);
    Camera cam;
    std::string error;
    CHECK(check_camera(cam, frame, error));
    cam.fstop = 0;
    CHECK_FALSE(check_camera(cam, frame, error));
    CHECK_THAT(error, Catch::Contains("f-stop"));
    cam = Camera();
    cam.lens = LensModel::Optical;
    cam.focus_distance = 0.01;  // inside the 50 mm focal length
    CHECK_FALSE(check_camera(cam, frame, error));
    CHECK_THAT(error, Catch::Contains("optical"));
    cam = Camera();
    // Far left, on a wide lens: the plane seen edge-on there.
    cam.focus_pixel = Imath::V2d(0, 270);
    cam.focal_length_mm = 18;
    cam.tilt_deg[1] = -70;
    CHECK_FALSE(check_camera(cam, frame, error));
    CHECK_THAT(error, Catch::Contains("edge-on"));
    cam = Camera();
    cam.split = { 10, 10, 10, 10, 2.0 };
    CHECK_FALSE(check_camera(cam, frame, error));
    CHECK_THAT(error, Catch::Contains("two different points"));
}

TEST_CASE("a tilted plane of focus is in focus where the ray of each pixel meets it")
{
    // A 960 x 540 frame on a 36 mm filmback: f_px = 50 / 36 * 960.
    const ROI frame(0, 960, 0, 540);
    Camera cam;
    cam.focal_length_mm = 50;
    cam.focus_distance = 4.0;
    cam.tilt_deg[0] = 10.0;  // the top away from the camera
    cam.tilt_deg[1] = -5.0;  // the right side nearer
    cam.focus_pixel = Imath::V2d(700, 100);
    const CircleOfConfusion coc(cam, frame);
    const double fpx = 50.0 / 36.0 * 960.0;
    // The plane through the focus point P0 with normal
    // (-tan(tilt_v), tan(tilt_h), 1); pixel (x, y) looks along
    // ((x + 0.5 - 480) / fpx, (y + 0.5 - 270) / fpx, 1).
    const double nx = -std::tan(-5.0 * M_PI / 180), ny = std::tan(10.0 * M_PI / 180);
    auto ray = [&](int x, int y) {
        return std::array<double, 2> { (x + 0.5 - 480) / fpx, (y + 0.5 - 270) / fpx };
    };
    const auto p0 = ray(700, 100);
    const double n_dot_p0 = 4.0 * (nx * p0[0] + ny * p0[1] + 1.0);
    CHECK(coc.diameter(4.0, 700, 100) == Approx(0.0).margin(1e-9));
    for (auto [x, y] :
         { std::pair { 0, 0 }, { 959, 0 }, { 0, 539 }, { 959, 539 }, { 300, 400 } }) {
        const auto r = ray(x, y);
        const double z_focus = n_dot_p0 / (nx * r[0] + ny * r[1] + 1.0);
        INFO("pixel " << x << "," << y << " focus " << z_focus);
        CHECK(coc.diameter(z_focus, x, y) == Approx(0.0).margin(1e-9));
        CHECK(coc.depth_at(3.0, x, y) > z_focus);
        CHECK(coc.diameter(coc.depth_at(3.0, x, y), x, y) == Approx(3.0));
    }
    // The top is focused farther than the bottom, the left farther than
    // the right.
    CHECK(coc.depth_at(0.0, 480, 0) > coc.depth_at(0.0, 480, 539));
    CHECK(coc.depth_at(0.0, 0, 270) > coc.depth_at(0.0, 959, 270));
}

TEST_CASE("a split diopter focuses beyond its line at its own distance")
{
    const ROI frame(0, 960, 0, 540);
    Camera cam;
    cam.focus_distance = 10.0;
    // A line across the frame from left to right: beyond it (on its right,
    // walking from the first point) is the lower half.
    cam.split = { 0, 270, 960, 270, 1.5 };
    const CircleOfConfusion coc(cam, frame);
    Camera near = cam, far = cam;
    near.split = far.split = SplitDiopter();
    near.focus_distance = 1.5;
    const CircleOfConfusion plain_near(near, frame), plain_far(far, frame);
    for (double z : { 0.7, 1.5, 4.0, 10.0, 200.0 }) {
        CHECK(coc.diameter(z, 100, 500) == Approx(plain_near.diameter(z, 100, 500)));
        CHECK(coc.diameter(z, 100, 260) == Approx(plain_far.diameter(z, 100, 260)));
        // Across the line, in between.
        const double c = coc.diameter(z, 100, 270);
        CHECK(c == Approx(0.5 * (plain_near.diameter(z, 100, 270) + plain_far.diameter(z, 100, 270))));
    }
}

TEST_CASE("an in-focus range stays sharp, and the blur beyond starts at its ends")
{
    Camera cam;
    cam.focal_length_mm = 85;
    cam.fstop = 1.4;
    cam.focus_distance = 4.0;
    cam.in_focus_range = 2.0;  // sharp from 3 to 5
    const ROI display(0, 960, 0, 540);
    const CircleOfConfusion coc(cam, display);
    for (const double z : { 3.0, 3.5, 4.0, 4.99, 5.0 })
        CHECK(coc.diameter(z, 10, 10) == 0.0);
    // In front, the blur of a lens focused at the near end; behind, at the
    // far end.
    Camera at_near = cam, at_far = cam;
    at_near.in_focus_range = at_far.in_focus_range = 0.0;
    at_near.focus_distance = 3.0;
    at_far.focus_distance  = 5.0;
    const CircleOfConfusion near(at_near, display), far(at_far, display);
    for (const double z : { 0.5, 1.0, 2.9 }) {
        CHECK(coc.diameter(z, 10, 10) == Approx(near.diameter(z, 10, 10)));
        CHECK(coc.depth_at(coc.diameter(z, 10, 10), 10, 10) == Approx(z));
    }
    for (const double z : { 5.1, 12.0, 1e4 }) {
        CHECK(coc.diameter(z, 10, 10) == Approx(far.diameter(z, 10, 10)));
        CHECK(coc.depth_at(coc.diameter(z, 10, 10), 10, 10) == Approx(z));
    }
    // A range reaching the camera keeps everything in front sharp.
    cam.in_focus_range = 10.0;
    CHECK(CircleOfConfusion(cam, display).diameter(0.01, 10, 10) == 0.0);
    CHECK(CircleOfConfusion(cam, display).diameter(20.0, 10, 10) > 0.0);
    cam.in_focus_range = -1.0;
    std::string error;
    CHECK_FALSE(check_camera(cam, display, error));
    CHECK(error == "the in-focus range must be a finite depth >= 0");
}
