// defocus's speed, in one run, as medians of interleaved rounds: every
// measurement runs once per round, so a busy moment of a shared machine
// slows them all alike and the ratios stay fair.
//
//   bench_speed [--rounds N] [--garden DIR] [--scene4k FILE]
//
// Prints: ms per input megapixel per filter at radius 4, 32, 128 and 256;
// the radius 128 / radius 4 ratio per aperture; the memory floor of
// spreading four 4096x2160 layers against spreading and compositing them;
// the read stage against a plain OpenEXR decode; whole frames of the garden
// scene and the 4K example (`defocus` as a process) and their peak memory;
// the 4K example flattened into one RGBA+Z image: its slice stage, and its
// whole frame against the layered one's; the 4K example written deep
// against its flat output; an 8-frame 4K sequence per frame against a
// frame alone; the goals of speed round 3, each beside its bar;
// reading large scene files (a million keyframes, ten thousand inputs, a
// frame list of huge steps, a million frames checked on disk); garden's
// error split into the region the pinhole view knows and the one only the
// lens reveals.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfThreading.h>
#include <OpenImageIO/argparse.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/sysutil.h>
#include <OpenImageIO/timer.h>

#include <defocus/composite/defocus_layers.h>
#include <defocus/color/color.h>
#include <defocus/io/aperture_files.h>
#include <defocus/io/frames.h>
#include <defocus/io/scene_io.h>
#include <defocus/layers/layering.h>
#include <defocus/io/shot_file.h>
#include <defocus/spread/spread.h>

#include "memory_floor.h"
#include "region_split.h"

using namespace OIIO;
using Strutil::fmt::format;

namespace {

/// A named measurement: returns seconds (or, for peak memory, bytes).
struct Measure {
    std::string name;
    std::function<double()> run;
    std::vector<double> samples;
    double median() const
    {
        std::vector<double> s = samples;
        std::nth_element(s.begin(), s.begin() + s.size() / 2, s.end());
        return s[s.size() / 2];
    }
};

/// One layer of premultiplied noise and a constant CoC radius.
struct TestLayer {
    ImageBuf color, radius;
    double megapixels() const { return color.spec().image_pixels() * 1e-6; }
};

TestLayer make_layer(int width, int height, float r)
{
    TestLayer layer { ImageBuf(ImageSpec(width, height, 4, TypeFloat)),
                      ImageBuf(ImageSpec(width, height, 1, TypeFloat)) };
    ImageBufAlgo::noise(layer.color, "uniform", 0.01f, 10.0f, false, 1);
    ImageBufAlgo::fill(layer.radius, { r });
    return layer;
}

double seconds(const std::function<bool()>& work)
{
    Timer timer;
    if (!work()) {
        std::fprintf(stderr, "bench_speed: a measurement failed\n");
        std::exit(1);
    }
    return timer();
}

/// Runs a command line through /bin/sh; returns wall seconds and sets
/// the child's peak resident memory in bytes (Linux counts a child's peak
/// from its parent's size at fork, so the parent must be small).
double run_process(const std::string& command, double& peak_bytes)
{
    Timer timer;
    const pid_t pid = fork();
    if (pid == 0) {
        execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
        _exit(127);
    }
    int status = 0;
    struct rusage usage {};
    wait4(pid, &status, 0, &usage);
    const double elapsed = timer();
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::fprintf(stderr, "bench_speed: failed: %s\n", command.c_str());
        std::exit(1);
    }
    peak_bytes = double(usage.ru_maxrss) * 1024.0;
    return elapsed;
}

/// A small process, forked before the benchmark allocates its layers, that
/// runs command lines for it, so that their peak memory is their own.
class Launcher {
public:
    Launcher()
    {
        int commands[2], results[2];
        if (pipe(commands) != 0 || pipe(results) != 0) {
            std::perror("bench_speed: pipe");
            std::exit(1);
        }
        m_pid = fork();
        if (m_pid == 0) {
            close(commands[1]);
            close(results[0]);
            FILE* in = fdopen(commands[0], "r");
            FILE* out = fdopen(results[1], "w");
            char line[8192];
            while (std::fgets(line, sizeof line, in)) {
                double peak = 0.0;
                const double t = run_process(Strutil::strip(line, "\n"), peak);
                std::fprintf(out, "%.9g %.0f\n", t, peak);
                std::fflush(out);
            }
            _exit(0);
        }
        close(commands[0]);
        close(results[1]);
        m_commands = fdopen(commands[1], "w");
        m_results = fdopen(results[0], "r");
    }
    ~Launcher()
    {
        std::fclose(m_commands);
        std::fclose(m_results);
        waitpid(m_pid, nullptr, 0);
    }
    /// As run_process().
    double run(const std::string& command, double& peak_bytes)
    {
        std::fprintf(m_commands, "%s\n", command.c_str());
        std::fflush(m_commands);
        double t = 0.0;
        if (std::fscanf(m_results, "%lf %lf", &t, &peak_bytes) != 2) {
            std::fprintf(stderr, "bench_speed: failed: %s\n", command.c_str());
            std::exit(1);
        }
        return t;
    }

private:
    pid_t m_pid = 0;
    FILE* m_commands = nullptr;
    FILE* m_results = nullptr;
};

/// Every part's channels decoded to float by OpenEXR alone, with as many
/// threads as defocus uses: what reading costs before defocus does
/// anything.
bool plain_openexr_decode(const std::string& filename)
{
    Imf::setGlobalThreadCount(int(Sysutil::hardware_concurrency()));
    Imf::MultiPartInputFile file(filename.c_str());
    for (int p = 0; p < file.parts(); ++p) {
        Imf::InputPart part(file, p);
        const Imath::Box2i dw = part.header().dataWindow();
        const size_t width = size_t(dw.max.x - dw.min.x + 1);
        const size_t height = size_t(dw.max.y - dw.min.y + 1);
        const Imf::ChannelList& channels = part.header().channels();
        size_t nchannels = 0;
        for (auto it = channels.begin(); it != channels.end(); ++it)
            ++nchannels;
        std::vector<float> pixels(width * height * nchannels);
        Imf::FrameBuffer frame;
        size_t c = 0;
        for (auto it = channels.begin(); it != channels.end(); ++it, ++c) {
            char* origin = reinterpret_cast<char*>(pixels.data() + c);
            const intptr_t first = (intptr_t(dw.min.y) * intptr_t(width) + dw.min.x)
                                   * intptr_t(nchannels * sizeof(float));
            frame.insert(it.name(), Imf::Slice(Imf::FLOAT, origin - first,
                                               nchannels * sizeof(float),
                                               width * nchannels * sizeof(float)));
        }
        part.setFrameBuffer(frame);
        part.readPixels(dw.min.y, dw.max.y);
    }
    return true;
}

bool read_stage(const std::string& filename)
{
    defocus::Scene scene;
    std::string error;
    return defocus::read_scene({ filename }, {}, scene, error);
}

/// The parts of the layered scene `layered` composited by depth into one
/// RGBA+Z image written to `flat`, as a renderer's flat beauty pass with
/// Z (oiiotool's --zover, part by part).
bool write_flattened(const std::string& layered, const std::string& flat)
{
    ImageBuf first(layered);
    if (!first.init_spec(layered, 0, 0))
        return false;
    ImageBuf result;
    for (int part = 0; part < first.nsubimages(); ++part) {
        ImageBuf layer(layered, part, 0);
        if (!layer.read(part, 0, true, TypeFloat))
            return false;
        if (!result.initialized()) {
            result = std::move(layer);
            continue;
        }
        // Outside its window a part reads as empty with Z 0: nothing there.
        ImageBuf both = ImageBufAlgo::zover(result, layer, true);
        if (both.has_error())
            return false;
        result = std::move(both);
    }
    return result.write(flat);
}

/// The layered scene `layered` with an `id` channel in each part (the
/// part's number, from 1): what --data-channels auto carries.
bool write_with_ids(const std::string& layered, const std::string& out)
{
    ImageBuf first(layered);
    if (!first.init_spec(layered, 0, 0))
        return false;
    std::vector<ImageBuf> parts;
    std::vector<ImageSpec> specs;
    for (int part = 0; part < first.nsubimages(); ++part) {
        ImageBuf layer(layered, part, 0);
        if (!layer.read(part, 0, true, TypeFloat))
            return false;
        const int n = layer.nchannels();
        std::vector<int> order(n + 1, -1);
        std::iota(order.begin(), order.end() - 1, 0);
        std::vector<float> values(n + 1, 0.0f);
        values[n] = float(part + 1);
        std::vector<std::string> names = layer.spec().channelnames;
        names.push_back("id");
        parts.push_back(ImageBufAlgo::channels(layer, n + 1, order, values, names));
        if (parts.back().has_error())
            return false;
        specs.push_back(parts.back().spec());
    }
    auto file = ImageOutput::create(out);
    if (!file || !file->open(out, int(specs.size()), specs.data()))
        return false;
    for (size_t p = 0; p < parts.size(); ++p)
        if ((p > 0 && !file->open(out, specs[p], ImageOutput::AppendSubimage))
            || !parts[p].write(file.get()))
            return false;
    return file->close();
}

/// The seconds of the "spread and composite" stage that `log` (defocus -v)
/// reports; 0 when it reports none.
double spread_stage_seconds(const std::string& log)
{
    const size_t at = log.find("spread and composite");
    return at == std::string::npos
               ? 0.0
               : std::strtod(log.c_str() + at + std::strlen("spread and composite"), nullptr);
}

/// The four 4096x2160 layers of the floor, as a scene with a camera that
/// gives blur up to 100 px: far field (CoC 60 px), hills in the lower half
/// (10 to 40 px), an in-focus post (10% of the width) and near leaves
/// (100 px, a quarter of the frame), layered: cropped to their content,
/// described and ordered back to front, as the layering stage hands them on.
struct FloorScene {
    defocus::LayeredScene scene;
    defocus::Camera camera;
};

FloorScene make_floor_scene(const std::vector<bench::FloorLayer>& layers)
{
    FloorScene s;
    // A 50 mm lens at f/1 on a 36 mm sensor: infinity blurs to 72 px.
    s.camera.focal_length_mm = 50.0;
    s.camera.fstop = 1.0;
    s.camera.sensor_width_mm = 36.0;
    s.camera.focus_distance = 4.0;
    const int width = 4096;
    const defocus::CircleOfConfusion coc(s.camera, OIIO::ROI(0, width, 0, 2160));
    const char* names[4] = { "far", "hills", "post", "leaves" };
    for (size_t i = 0; i < layers.size(); ++i) {
        const bench::FloorLayer& l = layers[i];
        defocus::Layer layer { names[i], ImageBuf(ImageSpec(l.width, l.height, 4, TypeFloat)),
                               ImageBuf(ImageSpec(l.width, l.height, 1, TypeFloat)) };
        layer.color.specmod().alpha_channel = 3;
        layer.color.set_pixels(ROI(0, l.width, 0, l.height, 0, 1, 0, 4), TypeFloat,
                               l.color.data());
        std::vector<float> depth(l.coc.size());
        std::transform(l.coc.begin(), l.coc.end(), depth.begin(),
                       [&](float diameter) { return float(coc.depth_at(diameter, 0, 0)); });  // a plane of focus: the same everywhere
        layer.depth.set_pixels(ROI(0, l.width, 0, l.height, 0, 1, 0, 1), TypeFloat, depth.data());
        defocus::crop_to_content(layer);
        s.scene.layers.push_back(std::move(layer));
    }
    s.scene.spec = ImageSpec(width, 2160, 4, TypeFloat);
    defocus::order_layers(s.scene, coc);
    return s;
}

std::string arg_quote(const std::string& s)
{
    return "'" + Strutil::replace(s, "'", "'\\''", true) + "'";
}

/// One goal's figure beside its bar: "met" when `figure` is at most `bar`
/// (or, with `at_least`, at least it).
void print_goal(const char* what, double figure, const char* unit, double bar,
                bool at_least = false)
{
    const bool met = at_least ? figure >= bar : figure <= bar;
    std::printf("  %-52s %7.2f%s (bar: %s %.2f%s) %s\n", what, figure, unit,
                at_least ? "at least" : "at most", bar, unit, met ? "met" : "NOT MET");
}

/// The goals of speed round 3 (issue 65), each figure from this run.
void print_round_three_goals(std::map<std::string, double>& median,
                             std::map<std::string, double>& peak)
{
    std::printf("\nspeed round 3 goals\n");
    const double zip = median["frame 4K zip"];
    print_goal("4K example, zip output / oiiotool copying it", zip / median["oiiotool copy 4K zip"],
               "x", 0.35);
    const double floors = median["process start"] + median["read 4K example (plain OpenEXR)"]
                          + median["floor"];
    std::printf("  %-52s %7.2fx (process start %.3f s, plain OpenEXR decode %.3f s, spread "
                "floor %.3f s; the output's deflate not counted)\n",
                "  the frame / the sum of its floors", zip / floors, median["process start"],
                median["read 4K example (plain OpenEXR)"], median["floor"]);
    print_goal("  its peak memory", peak["4K zip"] * 1e-6, " MB", 600.0);
    print_goal("4K example --deep / written flat", median["frame 4K deep out"] /
               median["frame 4K example"], "x", 1.5);
    print_goal("4K example with ids: --data-channels auto / without",
               median["frame 4K ids carried"] / median["frame 4K ids"], "x", 1.5);
    for (const char* soft : { "tent", "smooth" })
        print_goal(format("{} / disc, spread stage, 1024x540 noise, radius 128", soft).c_str(),
                   median[format("stage {} r128", soft)] / median["stage disc r128"], "x", 3.0);
    print_goal("8-frame 4K sequence: frame alone / frame in sequence",
               zip / median["sequence 4K, per frame"], "x", 1.6, true);
}

/// Garden's error split into the region the pinhole view knows and the one
/// only the lens reveals (fidelity/region_split.h), for the layers, flat
/// and deep at both foci, disc: what every change to slicing or filling
/// reports before and after.
void print_garden_split(const std::string& garden, const std::string& scratch)
{
    using namespace defocus_fidelity;
    std::printf("\ngarden, disc, known / revealed region PSNR (dB)\n");
    for (const char* focus : { "3", "1.25" }) {
        SceneSplit split;
        std::string error;
        if (!split_scene(garden,
                         garden + (std::string(focus) == "3" ? "/truth_focus3.exr"
                                                             : "/truth_focus1.25.exr"),
                         scratch,
                         [&](const std::string& input, const std::string& output) {
                             double peak = 0.0;
                             run_process(format("{} {} -o {} --focal 85 --fstop 1.4 --focus {} "
                                                "--aperture disc -q",
                                                DEFOCUS_BIN, arg_quote(input), arg_quote(output),
                                                focus),
                                         peak);
                             return true;
                         },
                         split, error)) {
            std::printf("  skipped: %s\n", error.c_str());
            return;
        }
        std::printf("  focus %-4s (%.1f%% revealed)", focus, 100.0 * split.layers.revealed_share);
        for (const auto& [input, r] : { std::pair("layers", split.layers),
                                         std::pair("flat", split.flat),
                                         std::pair("deep", split.deep) })
            std::printf("  %s %.2f / %.2f", input, r.known, r.revealed);
        std::printf("\n");
    }
}

}  // namespace

int main(int argc, const char* argv[])
{
    int rounds = 5;
    std::string garden = std::string(DEFOCUS_SHARED_DATA) + "/scenes/garden";
    std::string scene4k;
    ArgParse ap;
    ap.intro("bench_speed -- defocus's speed, as medians of interleaved rounds")
        .usage("bench_speed [options]");
    ap.arg("--rounds %d:N", &rounds).help("Rounds of every measurement (default: 5)");
    ap.arg("--garden %s:DIR", &garden).help("The garden scene's folder (skipped when absent)");
    ap.arg("--scene4k %s:FILE", &scene4k)
        .help("The 4K example scene (default: made with make_example_scene in a temporary folder)");
    std::string only;
    ap.arg("--only %s:TEXT", &only)
        .help("Run only the measurements whose name contains TEXT and print their medians "
              "(for profiling one of them)");
    if (ap.parse_args(argc, argv) < 0 || rounds < 1) {
        std::fprintf(stderr, "bench_speed: %s\n", ap.geterror().c_str());
        return 1;
    }
    Launcher launcher;
    const std::string scratch = Filesystem::temp_directory_path() + "/"
                                + Filesystem::unique_path("bench_speed_%%%%%%");
    Filesystem::create_directory(scratch);
    if (scene4k.empty()) {
        scene4k = scratch + "/scene4k.exr";
        double unused;
        std::printf("making the 4K example scene...\n");
        launcher.run(format("{} --width 3840 --height 2160 {} > /dev/null", MAKE_EXAMPLE_SCENE_BIN,
                           arg_quote(scene4k)),
                    unused);
    }

    std::vector<Measure> measures;
    auto add = [&](const std::string& name, std::function<double()> run) {
        measures.push_back({ name, std::move(run), {} });
    };

    // Filters on one 2048x1080 layer (a quarter of that for the filters
    // whose cost grows with the radius), per input megapixel.
    const int radii[] = { 4, 32, 128, 256 };
    std::map<int, TestLayer> layers, small_layers;
    for (int r : radii) {
        layers[r] = make_layer(2048, 1080, float(r));
        small_layers[r] = make_layer(1024, 540, float(r));
    }
    auto disc = std::make_shared<defocus::ApertureProfile>(defocus::Aperture());
    defocus::Aperture hexagon_aperture;
    hexagon_aperture.shape = defocus::ApertureShape::Polygon;
    auto hexagon = std::make_shared<defocus::ApertureProfile>(hexagon_aperture);
    auto mask = std::make_shared<defocus::MaskProfile>();
    std::string error;
    if (!defocus::read_aperture_mask(std::string(EXAMPLES_DIR) + "/psf/blades7.exr", 1.0,
                                     defocus::luma_weights(nullptr), *mask, error)) {
        std::fprintf(stderr, "bench_speed: %s\n", error.c_str());
        return 1;
    }
    // As a frame spreads them: highlights in place.
    const defocus::HighlightTest highlights { defocus::exact_highlight_threshold,
                                              defocus::luma_weights(nullptr) };
    using Filter = std::function<bool(ImageBuf&, const TestLayer&)>;
    const std::vector<std::pair<std::string, Filter>> filters = {
        { "box", [](ImageBuf& out, const TestLayer& l) {
              return defocus::spread_box(out, l.color, l.radius); } },
        { "disc", [&](ImageBuf& out, const TestLayer& l) {
              return defocus::spread_aperture(out, l.color, l.radius, *disc, highlights); } },
        { "polygon", [&](ImageBuf& out, const TestLayer& l) {
              return defocus::spread_aperture(out, l.color, l.radius, *hexagon, highlights); } },
        { "mask", [&](ImageBuf& out, const TestLayer& l) {
              return defocus::spread_aperture(out, l.color, l.radius, *mask, highlights); } },
        { "disc, --spread exact", [&](ImageBuf& out, const TestLayer& l) {
              return defocus::spread_scanline(out, l.color, l.radius, *disc); } },
        { "tent", [](ImageBuf& out, const TestLayer& l) {
              return defocus::spread_smooth(out, l.color, l.radius, 2); } },
        { "smooth", [](ImageBuf& out, const TestLayer& l) {
              return defocus::spread_smooth(out, l.color, l.radius, 3); } },
    };
    for (const auto& [name, filter] : filters) {
        const bool small = name == "disc, --spread exact" || name == "tent" || name == "smooth";
        for (int r : radii) {
            const TestLayer& layer = small ? small_layers[r] : layers[r];
            add(format("filter {} r{}", name, r), [&, filter = filter] {
                return seconds([&] {
                           ImageBuf out;
                           return filter(out, layer);
                       })
                       / layer.megapixels();
            });
        }
    }

    // The floor, and the real thing on the same four layers.
    const std::vector<bench::FloorLayer> floor_layers = bench::make_floor_layers();
    const FloorScene floor_scene = make_floor_scene(floor_layers);
    add("floor", [&] { return bench::memory_floor(floor_layers); });
    // Rendered into one image, as a sequence renders frame after frame
    // (defocus does per worker): like the floor's accumulator, the frame
    // is not fresh memory after the first round.
    ImageBuf out;
    add("spread and composite, 4 layers 4096x2160", [&] {
        return seconds([&] {
            return defocus::defocus_layers(out, floor_scene.scene, floor_scene.camera);
        });
    });

    // Reading.
    const bool have_garden = Filesystem::exists(garden + "/layers.exr");
    std::vector<std::pair<std::string, std::string>> inputs = { { "4K example", scene4k } };
    if (have_garden)
        inputs.insert(inputs.begin(), { "garden", garden + "/layers.exr" });
    for (const auto& [name, file] : inputs) {
        add(format("read {} (defocus)", name), [file = file] {
            return seconds([&] { return read_stage(file); });
        });
        add(format("read {} (plain OpenEXR)", name), [file = file] {
            return seconds([&] { return plain_openexr_decode(file); });
        });
    }

    // The 4K example as most renders reach compositing: one flat RGBA+Z
    // image, cut into layers again by the slice stage (layering, mixed
    // pixels, hidden-background fills), here alone, in-process.
    const std::string example_camera = "--focal 50 --fstop 1.8 --focus 4";
    const std::string flat4k = scratch + "/scene4k_flat.exr";
    defocus::Scene flat_scene;
    if (!write_flattened(scene4k, flat4k)
        || !defocus::read_scene({ flat4k }, {}, flat_scene, error)) {
        std::fprintf(stderr, "bench_speed: %s: cannot flatten the 4K example %s\n",
                     flat4k.c_str(), error.c_str());
        return 1;
    }
    const std::string ids4k = scratch + "/scene4k_ids.exr";
    if (!write_with_ids(scene4k, ids4k)) {
        std::fprintf(stderr, "bench_speed: %s: cannot write the 4K example with ids\n",
                     ids4k.c_str());
        return 1;
    }
    defocus::Camera flat_camera;
    flat_camera.focal_length_mm = 50.0;
    flat_camera.fstop = 1.8;
    flat_camera.focus_distance = 4.0;
    add("slice 4K flat", [&] {
        defocus::Scene scene = flat_scene;
        const defocus::CircleOfConfusion coc(flat_camera, scene.spec.roi_full());
        defocus::LayeredScene layered;
        defocus::Slicing slicing;
        std::string why;
        return seconds([&] {
            return defocus::decompose_layers(std::move(scene), coc, {}, layered, slicing, why);
        });
    });

    // Whole frames, as a user runs them.
    std::map<std::string, double> peak;
    const std::vector<std::pair<std::string, std::string>> frames = [&] {
        std::vector<std::pair<std::string, std::string>> f;
        if (have_garden)
            f.push_back({ "garden", format("{} {} -o {}/garden.exr --focal 85 --fstop 1.4 --focus 3 -q",
                                           DEFOCUS_BIN, arg_quote(garden + "/layers.exr"),
                                           arg_quote(scratch)) });
        for (const auto& [name, file] : { std::pair { "4K example", scene4k },
                                          std::pair { "4K flat", flat4k } })
            f.push_back({ name, format("{} {} -o {}/4k.exr {} --compression none -q",
                                       DEFOCUS_BIN, arg_quote(file), arg_quote(scratch),
                                       example_camera) });
        f.push_back({ "4K deep out", format("{} {} -o {}/4k.exr {} --compression none --deep -q",
                                            DEFOCUS_BIN, arg_quote(scene4k), arg_quote(scratch),
                                            example_camera) });
        // As most users write it: zip, OpenEXR's default and the example's.
        f.push_back({ "4K zip", format("{} {} -o {}/4k.exr {} -q", DEFOCUS_BIN,
                                       arg_quote(scene4k), arg_quote(scratch), example_camera) });
        // Data channels: the 4K example with an id in each part, carried
        // and not.
        for (const auto& [name, flags] : { std::pair { "4K ids", "" },
                                           std::pair { "4K ids carried", " --data-channels auto" } })
            f.push_back({ name, format("{} {} -o {}/4k.exr {}{} -q", DEFOCUS_BIN,
                                       arg_quote(ids4k), arg_quote(scratch), example_camera,
                                       flags) });
        // Compositing per cell of the aperture, automatic, against one cell
        // (today's method): the garden at focus 1.25 and the 4K example.
        for (const char* cells : { "1", "0" }) {
            if (have_garden)
                f.push_back({ format("garden f1.25 cells {}", cells),
                              format("{} {} -o {}/garden.exr --focal 85 --fstop 1.4 --focus 1.25 "
                                     "--aperture-cells {} -q",
                                     DEFOCUS_BIN, arg_quote(garden + "/layers.exr"),
                                     arg_quote(scratch), cells) });
            f.push_back({ format("4K cells {}", cells),
                          format("{} {} -o {}/4k.exr {} --aperture-cells {} -q", DEFOCUS_BIN,
                                 arg_quote(scene4k), arg_quote(scratch), example_camera, cells) });
        }
        return f;
    }();
    for (const auto& [name, command] : frames)
        add(format("frame {}", name), [&, name = name, command = command] {
            double bytes = 0.0;
            const double t = launcher.run(command, bytes);
            peak[name] = std::max(peak[name], bytes);
            return t;
        });
    // What the 4K zip frame is measured against: a plain copy of the same
    // file by oiiotool, and starting the process.
    add("oiiotool copy 4K zip", [&] {
        double unused = 0.0;
        return launcher.run(format("oiiotool -a {} --compression zip -o {}/copy.exr",
                                   arg_quote(scene4k), arg_quote(scratch)),
                            unused);
    });
    add("process start", [&] {
        double unused = 0.0;
        return launcher.run(format("{} --version > /dev/null", DEFOCUS_BIN), unused);
    });
    // The soft apertures' spread stage against the disc's, as -v reports
    // it: a 1024x540 noise layer at one depth, blurred to radius 128.
    {
        ImageBuf noise(ImageSpec(1024, 540, 5, TypeFloat));
        ImageBufAlgo::noise(noise, "uniform", 0.0f, 1.0f, false, 1);
        ImageBufAlgo::fill(noise, { 1.0f }, ROI(0, 1024, 0, 540, 0, 1, 3, 4));
        ImageBufAlgo::fill(noise, { 10.0f }, ROI(0, 1024, 0, 540, 0, 1, 4, 5));
        noise.specmod().channelnames = { "R", "G", "B", "A", "Z" };
        noise.write(scratch + "/noise.exr");
    }
    for (const char* aperture : { "disc", "tent", "smooth" })
        add(format("stage {} r128", aperture), [&, aperture] {
            // 50 mm f/0.25 on 1024 px, focus 1 m: depth 10 m blurs to a
            // CoC of 256 px.
            double unused = 0.0;
            const std::string log = scratch + "/stage.log";
            launcher.run(format("{} {}/noise.exr -o {}/noise_out.exr --focal 50 --fstop 0.25 "
                                "--focus 1 --max-blur 1000 --layers 1 --aperture {} -v > {} 2>&1",
                                DEFOCUS_BIN, arg_quote(scratch), arg_quote(scratch), aperture,
                                arg_quote(log)),
                         unused);
            std::string text;
            Filesystem::read_text_file(log, text);
            return spread_stage_seconds(text);
        });
    // A sequence of 8 frames of the 4K example, per frame, beside the
    // frame run alone ("frame 4K zip"): what running frames side by side
    // gains.
    constexpr int sequence_length = 8;
    for (int i = 1; i <= sequence_length; ++i)
        Filesystem::copy(scene4k, format("{}/seq.{:04d}.exr", scratch, i));
    add("sequence 4K, per frame", [&] {
        double bytes = 0.0;
        return launcher.run(format("{} {}/seq.#.exr --frames 1-{} -o {}/seq_out.#.exr {} -q",
                                   DEFOCUS_BIN, arg_quote(scratch), sequence_length,
                                   arg_quote(scratch), example_camera),
                            bytes)
               / sequence_length;
    });

    // Lens effects, each a whole frame beside the plain disc's, on the
    // garden (or a 1280x720 example scene without it).
    std::string effects_scene = garden + "/layers.exr",
                effects_camera = "--focal 85 --fstop 1.4 --focus 1.25";
    if (!have_garden) {
        effects_scene = scratch + "/scene720.exr";
        double unused;
        launcher.run(format("{} --width 1280 --height 720 {} > /dev/null", MAKE_EXAMPLE_SCENE_BIN,
                            arg_quote(effects_scene)),
                     unused);
        effects_camera = "--focal 50 --fstop 1.8 --focus 4";
    }
    const std::vector<std::pair<std::string, std::string>> effects = {
        { "plain disc", "" },
        { "--focus-tilt 10,5", "--focus-tilt 10,5" },
        { "--split-diopter", "--split-diopter 0,270,960,270:3" },
        { "--axial-ca 0.2", "--axial-ca 0.2" },
        { "--lateral-ca 0.002", "--lateral-ca 0.002" },
        { "--axial-ca + --lateral-ca", "--axial-ca 0.2 --lateral-ca 0.002" },
        { "--cateye 1", "--cateye 1" },
        { "--aperture polygon", "--aperture polygon" },
    };
    for (const auto& [name, flags] : effects)
        add(format("effect {}", name), [&, flags = flags] {
            double unused = 0.0;
            return launcher.run(format("{} {} -o {}/effect.exr {} {} -q", DEFOCUS_BIN,
                                       arg_quote(effects_scene), arg_quote(scratch),
                                       effects_camera, flags),
                                unused);
        });

    // Scene files at the scale of a long shot: each must read in linear
    // time (target: under 2 s each).
    const std::string input_name = Filesystem::filename(scene4k);
    std::string keyframes_text, inputs_text;
    for (int frame = 1; frame <= 1000000; ++frame)
        keyframes_text += format("{}\"{}\": {}", frame == 1 ? "" : ", ", frame,
                                 1.0 + frame * 1e-6);
    keyframes_text = format("{{\"version\": 1, \"inputs\": [\"{}\"], \"scene\": {{\"frames\": "
                            "\"1-1000000\"}}, \"camera\": {{\"focus\": {{{}}}}}}}",
                            input_name, keyframes_text);
    for (int i = 0; i < 10000; ++i)
        inputs_text += format("{}\"{}\"", i == 0 ? "" : ", ", input_name);
    inputs_text = format("{{\"version\": 1, \"inputs\": [{}], \"camera\": {{\"focus\": 3}}}}",
                         inputs_text);
    const std::string huge_steps = "{\"version\": 1, \"inputs\": [\"" + input_name
                                   + "\"], \"scene\": {\"frames\": \"1-2147483647x2147483646,"
                                     "-1000000000-1000000000x999999999\"}}";
    // Every frame of every pattern is looked up: three frames on disk of a
    // million listed, the rest skipped.
    const std::string sequence_folder = scratch + "/sequence";
    Filesystem::create_directory(sequence_folder);
    for (int frame : { -1000000, -500000, -1, 1, 500000, 1000000 })
        for (const char* name : { "beauty", "depth" })
            Filesystem::write_text_file(format("{}/{}.{:04d}.exr", sequence_folder, name, frame),
                                        "");
    auto sequence_frames = [&](const char* frames) {
        return format("{{\"version\": 1, \"inputs\": [\"{0}/beauty.#.exr\"], \"scene\": "
                      "{{\"depth\": \"{0}/depth.%04d.exr\", \"frames\": \"{1}\", "
                      "\"missing_frames\": \"skip\"}}}}",
                      sequence_folder, frames);
    };
    // The frame number in a folder's name: the folders are listed.
    for (int frame : { 1, 500000, 1000000 }) {
        const std::string take = format("{}/take.{:04d}", sequence_folder, frame);
        Filesystem::create_directory(take);
        Filesystem::write_text_file(take + "/beauty.exr", "");
    }
    const std::string take_frames =
        format("{{\"version\": 1, \"inputs\": [\"{0}/take.#/beauty.exr\"], \"scene\": "
               "{{\"frames\": \"1-1000000\", \"missing_frames\": \"skip\"}}}}",
               sequence_folder);
    const std::vector<std::pair<std::string, std::string>> scene_files = {
        { "1,000,000 keyframes", keyframes_text },
        { "10,000 inputs", inputs_text },
        { "frames of huge steps", huge_steps },
        { "1,000,000 frames, 3 on disk", sequence_frames("1-1000000") },
        { "1,000,000 negative frames, 3 on disk", sequence_frames("-1000000--1") },
        { "1,000,000 folders, 3 on disk", take_frames },
    };
    for (const auto& [name, text] : scene_files)
        add("scene file " + name, [&, text = text] {
            return seconds([&] {
                defocus::Shot shot;
                std::vector<int> frames;
                std::string why;
                return defocus::parse_shot(text, Filesystem::parent_path(scene4k), "bench.dof",
                                           shot, why)
                       && defocus::shot_frames(shot, frames, why);
            });
        });

    if (!only.empty())
        measures.erase(std::remove_if(measures.begin(), measures.end(),
                                      [&](const Measure& m) {
                                          return m.name.find(only) == std::string::npos;
                                      }),
                       measures.end());
    for (int round = 0; round < rounds; ++round) {
        std::printf("round %d of %d\n", round + 1, rounds);
        std::fflush(stdout);
        for (Measure& m : measures)
            m.samples.push_back(m.run());
    }
    std::map<std::string, double> median;
    for (const Measure& m : measures)
        median[m.name] = m.median();
    if (!only.empty()) {
        for (const Measure& m : measures)
            std::printf("%-45s %10.1f ms\n", m.name.c_str(), 1e3 * m.median());
        Filesystem::remove_all(scratch);
        return 0;
    }

    std::printf("\nmedians of %d interleaved rounds, %d threads\n", rounds,
                int(Sysutil::hardware_concurrency()));
    std::printf("\nms per input megapixel (2048x1080 layer; exact, tent, smooth: 1024x540)\n");
    std::printf("%-22s %9s %9s %9s %9s\n", "filter", "r 4", "r 32", "r 128", "r 256");
    for (const auto& [name, filter] : filters) {
        std::printf("%-22s", name.c_str());
        for (int r : radii)
            std::printf(" %9.1f", 1e3 * median[format("filter {} r{}", name, r)]);
        std::printf("\n");
    }
    std::printf("\nradius 128 / radius 4, per input megapixel (target: at most 1.3)\n");
    for (const char* name : { "box", "disc", "polygon", "mask" })
        std::printf("  %-8s %.2f\n", name,
                    median[format("filter {} r128", name)] / median[format("filter {} r4", name)]);
    const double floor = median["floor"];
    const double spread = median["spread and composite, 4 layers 4096x2160"];
    std::printf("\nfour 4096x2160 layers, blur up to 100 px, disc\n");
    std::printf("  memory floor            %8.1f ms\n", 1e3 * floor);
    std::printf("  spread and composite    %8.1f ms  (%.1fx the floor; target: at most 4x)\n",
                1e3 * spread, spread / floor);
    std::printf("\nread stage (target: at most 1.5x a plain OpenEXR decode)\n");
    for (const auto& [name, file] : inputs) {
        const double ours = median[format("read {} (defocus)", name)];
        const double plain = median[format("read {} (plain OpenEXR)", name)];
        std::printf("  %-12s %8.1f ms, plain OpenEXR %8.1f ms: %.2fx\n", name.c_str(), 1e3 * ours,
                    1e3 * plain, ours / plain);
    }
    std::printf("\nwhole frames (defocus as a process)\n");
    for (const auto& [name, command] : frames)
        std::printf("  %-12s %8.3f s, peak memory %6.0f MB\n", name.c_str(),
                    median["frame " + name], peak[name] * 1e-6);
    if (!have_garden)
        std::printf("  (garden skipped: no %s)\n", garden.c_str());
    std::printf("  4K flat: %.2fx the layered 4K example (target: at most 1.5x); its slice "
                "stage %.3f s (target: at most 0.5 s)\n",
                median["frame 4K flat"] / median["frame 4K example"], median["slice 4K flat"]);
    std::printf("  4K frame's layers as float RGBA: %.0f MB (target: peak at most twice that)\n",
                4.0 * 4096 * 2160 * 16 * 1e-6);
    std::printf("  4K example written deep (--deep): %.2fx the time and %.2fx the peak memory "
                "of its flat output\n",
                median["frame 4K deep out"] / median["frame 4K example"],
                peak["4K deep out"] / peak["4K example"]);
    std::printf("\nautomatic aperture cells / one cell, whole processes (issue 61)\n");
    if (have_garden)
        std::printf("  garden, focus 1.25: %.2fx the time (target: at most 2x)\n",
                    median["frame garden f1.25 cells 0"] / median["frame garden f1.25 cells 1"]);
    std::printf("  4K example: %.2fx the time (target: at most 1.5x), %.2fx the peak memory "
                "(target: at most 1.3x)\n",
                median["frame 4K cells 0"] / median["frame 4K cells 1"],
                peak["4K cells 0"] / peak["4K cells 1"]);
    std::printf("\nlens effects, whole frames of %s (%s)\n",
                have_garden ? "the garden" : "a 1280x720 example scene", effects_camera.c_str());
    const double plain_disc = median["effect plain disc"];
    for (const auto& [name, flags] : effects)
        std::printf("  %-28s %8.3f s  %5.2fx the plain disc\n", name.c_str(),
                    median["effect " + name], median["effect " + name] / plain_disc);
    print_round_three_goals(median, peak);
    std::printf("\nscene files, read and their frames listed (target: under 2 s each)\n");
    for (const auto& [name, text] : scene_files)
        std::printf("  %-24s %8.3f s\n", name.c_str(), median["scene file " + name]);
    if (have_garden)
        print_garden_split(garden, scratch);
    Filesystem::remove_all(scratch);
    return 0;
}
