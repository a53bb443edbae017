#include "test_support.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <unistd.h>

#include <catch2/catch.hpp>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <defocus/shot/setting_words.h>
#include <defocus/io/image_input.h>
#include <defocus/layers/layering.h>
#include <defocus/io/shot_assets.h>
#include <defocus/io/shot_file.h>

namespace defocus_test {

using namespace OIIO;

defocus::LayeredScene layered_scene(defocus::Scene scene, const defocus::Camera& camera)
{
    defocus::LayeredScene out;
    const defocus::CircleOfConfusion coc(camera, scene.spec.roi_full());
    defocus::Slicing slicing;
    std::string error;
    if (!defocus::decompose_layers(std::move(scene), coc, {}, out, slicing, error))
        throw std::runtime_error(error);
    return out;
}

ImageBuf read_image(const std::string& file)
{
    ImageBuf image;
    std::string error;
    if (!defocus::read_image_file(file, "the image", image, error))
        return ImageBuf();
    return image;
}

ImageSpec read_spec(const std::string& file, int subimage)
{
    auto in = OIIO::ImageInput::open(file);
    if (!in || !in->seek_subimage(subimage, 0))
        return ImageSpec();
    return in->spec();
}

int count_subimages(const std::string& file)
{
    auto in = OIIO::ImageInput::open(file);
    int n = 0;
    while (in && in->seek_subimage(n, 0))
        ++n;
    return n;
}

ImageBuf zero_image(const ROI& roi, int nchannels)
{
    ImageSpec spec(roi.width(), roi.height(), nchannels, TypeFloat);
    spec.x = roi.xbegin;
    spec.y = roi.ybegin;
    spec.full_x = roi.xbegin;
    spec.full_y = roi.ybegin;
    ImageBuf image(spec);
    ImageBufAlgo::zero(image);
    return image;
}

defocus::Aperture hexagon()
{
    defocus::Aperture a;
    a.shape = defocus::ApertureShape::Polygon;
    a.blades = 6;
    a.rotation_deg = 10.0;
    return a;
}

ImageBuf impulse()
{
    ImageBuf image = zero_image(ROI(0, 1, 0, 1), 4);
    const float one[4] = { 1, 1, 1, 1 };
    image.setpixel(0, 0, one);
    return image;
}

ImageBuf constant_radius(const ROI& roi, float r)
{
    ImageBuf radius = zero_image(roi, 1);
    ImageBufAlgo::fill(radius, { r });
    return radius;
}

double largest_footprint_step(const std::function<ImageBuf(float)>& spread_at, float r0,
                              float step, int count)
{
    ImageBuf previous = spread_at(r0);
    double largest = 0.0;
    for (int i = 1; i <= count; ++i) {
        const ImageBuf next = spread_at(r0 + step * i);
        const ROI all = roi_union(next.roi(), previous.roi());
        double moved = 0.0;
        for (int y = all.ybegin; y < all.yend; ++y)
            for (int x = all.xbegin; x < all.xend; ++x) {
                float a[4], b[4];
                next.getpixel(x, y, a);
                previous.getpixel(x, y, b);
                moved += std::abs(a[0] - b[0]);
            }
        largest = std::max(largest, moved);
        previous = next;
    }
    return largest;
}

void random_layer(const ROI& roi, double rmin, double rmax, unsigned seed, ImageBuf& color,
                  ImageBuf& radius)
{
    color = zero_image(roi, 4);
    radius = zero_image(roi, 1);
    Random rng(seed);
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            float v[4];
            for (float& c : v)
                c = float(0.01 + 10.0 * rng.uniform());
            color.setpixel(x, y, v);
            const float r = float(rmin + (rmax - rmin) * rng.uniform());
            radius.setpixel(x, y, &r);
        }
}

ImageBuf direct_sum(const ImageBuf& color, const ImageBuf& radius, const ImageBuf& like,
                    const std::function<defocus::Footprint(int, int, double)>& footprint)
{
    ImageBuf direct(like.spec());
    OIIO::ImageBufAlgo::zero(direct);
    const ROI roi = color.roi();
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            float v[4], r;
            color.getpixel(x, y, v);
            radius.getpixel(x, y, &r);
            const defocus::Footprint fp = footprint(x, y, double(r));
            for (int j = 0; j < fp.height; ++j)
                for (int i = 0; i < fp.width; ++i) {
                    float out[4];
                    direct.getpixel(x + fp.x0 + i, y + fp.y0 + j, out);
                    for (int c = 0; c < 4; ++c)
                        out[c] += float(fp.at(i, j) * v[c]);
                    direct.setpixel(x + fp.x0 + i, y + fp.y0 + j, out);
                }
        }
    return direct;
}

void highlight_on_dim_field(const ROI& roi, const Imath::V2i& at, ImageBuf& color,
                            ImageBuf& radius)
{
    random_layer(roi, 40.0, 40.0, 3, color, radius);
    OIIO::ImageBufAlgo::mul(color, color, 1e-3f);
    const float bright[4] = { 1000.0f, 1000.0f, 1000.0f, 1.0f };
    color.setpixel(at.x, at.y, bright);
}

defocus::Camera synthetic_camera(double focus)
{
    defocus::Camera cam;
    cam.focal_length_mm = 100;
    cam.fstop = 1;
    cam.sensor_width_mm = 36;
    cam.focus_distance = focus;
    return cam;
}

double Random::uniform()
{
    m_state = m_state * 6364136223846793005ull + 1442695040888963407ull;
    return double(m_state >> 11) * (1.0 / 9007199254740992.0);
}

float largest_difference(const ImageBuf& a, const ImageBuf& b)
{
    return float(ImageBufAlgo::compare(a, b, 0.0f, 0.0f).maxerror);
}

double channel_sum(const ImageBuf& image, int c)
{
    double sum = 0.0;
    for (ImageBuf::ConstIterator<float> it(image); !it.done(); ++it)
        sum += it[c];
    return sum;
}

double worst_relative_error(const ImageBuf& a, const ImageBuf& b, double rel,
                            double abs)
{
    const ROI all = roi_union(a.roi(), b.roi());
    double worst = 0.0;
    std::vector<float> pa(a.nchannels()), pb(b.nchannels());
    for (int y = all.ybegin; y < all.yend; ++y)
        for (int x = all.xbegin; x < all.xend; ++x) {
            a.getpixel(x, y, pa.data());  // zero outside the data window
            b.getpixel(x, y, pb.data());
            for (int c = 0; c < b.nchannels(); ++c) {
                const double e = std::abs(double(pa[c]) - pb[c])
                                 / (std::abs(pb[c]) * rel + abs);
                if (!(e <= worst))
                    worst = e;  // NaN propagates
            }
        }
    return worst;
}

namespace {
double srgb_encode_clamped(double v)
{
    v = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
    return std::min(1.0, std::max(0.0, v));
}
}  // namespace

double garden_psnr(const ImageBuf& result, const ImageBuf& truth, int dx, int dy)
{
    const ImageSpec& t = truth.spec();
    double sq = 0.0;
    float a[4], b[4];
    for (int y = t.full_y; y < t.full_y + t.full_height; ++y)
        for (int x = t.full_x; x < t.full_x + t.full_width; ++x) {
            result.getpixel(x + dx, y + dy, a, 3);
            truth.getpixel(x, y, b, 3);
            for (int c = 0; c < 3; ++c) {
                const double d = srgb_encode_clamped(a[c]) - srgb_encode_clamped(b[c]);
                sq += d * d;
            }
        }
    const double mse = sq / (3.0 * t.full_width * t.full_height);
    return 10.0 * std::log10(1.0 / mse);
}

int run(const std::string& command, std::string& output)
{
    output.clear();
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe)
        return -1;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0)
        output.append(buf.data(), n);
    const int status = pclose(pipe);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

const std::string defocus_bin = DEFOCUS_BIN;

std::string this_host()
{
    char name[256] = {};
    gethostname(name, sizeof name - 1);
    return OIIO::Strutil::replace(name, ".", "_", true);
}

ImageSpec rgbaz_spec(int width, int height)
{
    ImageSpec spec(width, height, 5, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "Z" };
    spec.alpha_channel = 3;
    spec.z_channel = 4;
    return spec;
}

std::string two_depth_scene(const std::string& dir)
{
    ImageBuf image(rgbaz_spec(20, 20));
    ImageBufAlgo::fill(image, { 0.5f, 0.5f, 0.5f, 1.0f, 2.0f });
    ImageBufAlgo::fill(image, { 0.2f, 0.4f, 0.8f, 1.0f, 6.0f }, ROI(10, 20, 0, 20));
    const std::string path = dir + "/two_depths.exr";
    REQUIRE(image.write(path));
    return path;
}

defocus::Shot shot_with(const std::vector<std::string>& inputs, const Settings& settings)
{
    defocus::Shot shot;
    shot.inputs = inputs;
    std::string error;
    for (const auto& [name, value] : settings) {
        INFO(name << " = " << value);
        REQUIRE(defocus::set_shot_setting(shot, name, value, error));
    }
    return shot;
}

bool render_with(const std::vector<std::string>& inputs, const Settings& settings,
                 defocus::FrameResult& result, std::string& error, int frame)
{
    defocus::Shot shot;
    shot.inputs = inputs;
    for (const auto& [name, value] : settings)
        if (!defocus::set_shot_setting(shot, name, value, error))
            return false;
    return render_shot(shot, result, error, frame);
}

bool render_shot(const defocus::Shot& shot, defocus::FrameResult& result, std::string& error,
                 int frame)
{
    defocus::ShotAssets assets;
    return defocus::check_shot(shot, error) && defocus::read_shot_assets(shot, assets, error)
           && defocus::render_frame(shot, frame, assets, result, error);
}

ImageBuf rendered(const std::string& input, const Settings& settings, int frame)
{
    defocus::FrameResult result;
    std::string error;
    const bool ok = render_with(input, settings, result, error, frame);
    INFO(error);
    REQUIRE(ok);
    return result.image;
}

bool no_nan(const ImageBuf& image)
{
    const ImageBufAlgo::PixelStats stats = ImageBufAlgo::computePixelStats(image);
    for (size_t c = 0; c < stats.nancount.size(); ++c)
        if (stats.nancount[c] || stats.infcount[c])
            return false;
    return true;
}

void write_uniform_image(const std::string& path, const std::vector<std::string>& channels,
                         const std::vector<float>& pixel, int width, int height, TypeDesc type)
{
    ImageSpec spec(width, height, int(channels.size()), type);
    spec.channelnames = channels;
    ImageBuf image(spec);
    ImageBufAlgo::fill(image, pixel);
    REQUIRE(image.write(path));
}

std::string dof_error(const std::string& text, const std::string& directory)
{
    defocus::Shot shot;
    std::string error;
    INFO(text);
    CHECK_FALSE(defocus::parse_shot(text, directory, "shot.dof", shot, error));
    CHECK(Strutil::starts_with(error, "shot.dof: "));
    CHECK(error.find('\n') == std::string::npos);
    return error;
}

std::string example_scene()
{
    static std::string path;
    if (path.empty()) {
        const std::string file = scratch_dir("example") + "/scene.exr";
        std::string log;
        if (run(std::string(MAKE_EXAMPLE_SCENE_BIN) + " " + file + " --width 320 --height 180",
                log)
            != 0)
            throw std::runtime_error("make_example_scene failed: " + log);
        path = file;
    }
    return path;
}

bool one_line_naming(const std::string& text, const std::string& what)
{
    return text.find(what) != std::string::npos && text.find('\n') == text.size() - 1;
}

bool one_line_error(const std::string& error, const std::string& what)
{
    return command_line_words(error).find(what) != std::string::npos
           && error.find('\n') == std::string::npos;
}

std::string command_line_words(const std::string& message)
{
    return defocus::in_words(message, defocus::SettingForm::CommandLine);
}

std::string shared_data()
{
    const char* env = std::getenv("DEFOCUS_SHARED_DATA");
    const std::string dir = env ? env : DEFOCUS_SHARED_DATA;
    return Filesystem::is_directory(dir) ? dir : "";
}

std::string scratch_dir(const std::string& name)
{
    // CTest runs test cases as parallel processes: each gets its own root,
    // removed when it exits.
    struct ProcessRoot {
        std::string path = std::string(DEFOCUS_TEST_SCRATCH) + "/" + std::to_string(getpid());
        ~ProcessRoot() { Filesystem::remove_all(path); }
    };
    static const ProcessRoot root;
    const std::string dir = root.path + "/" + name;
    Filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

void write_exr_header_only(const std::string& path, int width, int height)
{
    std::string file("\x76\x2f\x31\x01\x02\0\0\0", 8);  // magic, version 2, scanline
    auto put = [&](const void* data, size_t size) {
        file.append(static_cast<const char*>(data), size);
    };
    auto attribute = [&](const std::string& name, const std::string& type,
                         const std::string& value) {
        file += name + '\0' + type + '\0';
        const int32_t size = int32_t(value.size());
        put(&size, 4);
        file += value;
    };
    auto bytes = [](std::initializer_list<int32_t> values) {
        return std::string(reinterpret_cast<const char*>(values.begin()), values.size() * 4);
    };
    std::string channels;
    for (const char* name : { "A", "B", "G", "R", "Z" })
        channels += std::string(name) + '\0' + bytes({ 1 /* half */, 0, 1, 1 });
    channels += '\0';
    const std::string box = bytes({ 0, 0, width - 1, height - 1 });
    const float one = 1.0f, centre[2] = { 0.0f, 0.0f };
    attribute("channels", "chlist", channels);
    attribute("compression", "compression", std::string(1, '\3'));  // zip: 16 rows a chunk
    attribute("dataWindow", "box2i", box);
    attribute("displayWindow", "box2i", box);
    attribute("lineOrder", "lineOrder", std::string(1, '\0'));
    attribute("pixelAspectRatio", "float", std::string(reinterpret_cast<const char*>(&one), 4));
    attribute("screenWindowCenter", "v2f", std::string(reinterpret_cast<const char*>(centre), 8));
    attribute("screenWindowWidth", "float", std::string(reinterpret_cast<const char*>(&one), 4));
    file += '\0';
    const uint64_t chunks = (uint64_t(height) + 15) / 16;
    const uint64_t chunk_at = file.size() + chunks * 8;
    for (uint64_t c = 0; c < chunks; ++c)
        put(&chunk_at, 8);
    file += bytes({ 0, 4 }) + std::string(4, '\0');  // one chunk: row 0, 4 bytes
    if (!OIIO::Filesystem::write_binary_file(path, OIIO::cspan<char>(file.data(), file.size())))
        throw std::runtime_error("cannot write " + path);
}

}  // namespace defocus_test
