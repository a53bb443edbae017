#include "region_split.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include <OpenImageIO/imageio.h>

namespace defocus_fidelity {

using namespace OIIO;

namespace {

/// Every part of the EXR `path` as float pixels; false with `error`.
bool read_parts(const std::string& path, std::vector<ImageBuf>& parts, std::string& error)
{
    auto input = ImageInput::open(path);
    if (!input) {
        error = path + ": " + OIIO::geterror();
        return false;
    }
    int count = 0;
    while (input->seek_subimage(count, 0))
        ++count;
    input.reset();
    for (int i = 0; i < count; ++i) {
        ImageBuf part(path, i, 0);
        if (!part.read(i, 0, true, TypeFloat)) {
            error = path + ": " + part.geterror();
            return false;
        }
        parts.push_back(std::move(part));
    }
    if (parts.empty())
        error = path + ": no layers to read";
    return !parts.empty();
}

}  // namespace

bool cull_hidden(const std::string& in, const std::string& out, std::string& error,
                 double covered)
{
    std::vector<ImageBuf> parts;
    if (!read_parts(in, parts, error))
        return false;
    std::vector<int> alpha, depth;
    for (const ImageBuf& part : parts) {
        alpha.push_back(part.spec().channelindex("A"));
        depth.push_back(part.spec().channelindex("Z"));
        if (alpha.back() < 0 || depth.back() < 0) {
            error = in + ": a part without A and Z";
            return false;
        }
    }
    ROI all = parts[0].roi();
    for (const ImageBuf& part : parts)
        all = roi_union(all, part.roi());
    struct Seen {
        float z, a;
        size_t part;
    };
    std::vector<Seen> seen;
    for (int y = all.ybegin; y < all.yend; ++y)
        for (int x = all.xbegin; x < all.xend; ++x) {
            seen.clear();
            for (size_t p = 0; p < parts.size(); ++p)
                if (parts[p].roi().contains(x, y)) {
                    const float a = parts[p].getchannel(x, y, 0, alpha[p]);
                    if (a > 0.0f)
                        seen.push_back({ parts[p].getchannel(x, y, 0, depth[p]),
                                         std::min(a, 1.0f), p });
                }
            std::stable_sort(seen.begin(), seen.end(),
                             [](const Seen& a, const Seen& b) { return a.z < b.z; });
            double passing = 1.0;
            for (const Seen& s : seen) {
                if (passing <= 1.0 - covered) {
                    ImageBuf& part = parts[s.part];
                    std::vector<float> cleared(size_t(part.nchannels()), 0.0f);
                    cleared[size_t(depth[s.part])] = 1e10f;
                    part.setpixel(x, y, cleared.data());
                }
                passing *= 1.0 - s.a;
            }
        }
    std::vector<ImageSpec> specs;
    for (const ImageBuf& part : parts)
        specs.push_back(part.spec());
    auto output = ImageOutput::create(out);
    if (!output || !output->open(out, int(specs.size()), specs.data())) {
        error = out + ": " + (output ? output->geterror() : OIIO::geterror());
        return false;
    }
    for (size_t p = 0; p < parts.size(); ++p)
        if ((p > 0 && !output->open(out, specs[p], ImageOutput::AppendSubimage))
            || !output->write_image(TypeFloat, parts[p].localpixels())) {
            error = out + ": " + output->geterror();
            return false;
        }
    if (!output->close()) {
        error = out + ": " + output->geterror();
        return false;
    }
    return true;
}

std::vector<float> display_srgb(const ImageBuf& image, const ImageBuf* window_of)
{
    const ImageSpec& s = (window_of ? *window_of : image).spec();
    std::vector<float> out;
    out.reserve(size_t(s.full_width) * s.full_height * 3);
    float rgb[3];
    for (int y = s.full_y; y < s.full_y + s.full_height; ++y)
        for (int x = s.full_x; x < s.full_x + s.full_width; ++x) {
            image.getpixel(x, y, rgb, 3);
            for (float v : rgb) {
                const double c = std::clamp(double(v), 0.0, 1.0);
                out.push_back(float(c <= 0.0031308 ? 12.92 * c
                                                   : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055));
            }
        }
    return out;
}

std::vector<bool> revealed_pixels(const std::vector<float>& full, const std::vector<float>& culled)
{
    std::vector<bool> revealed(full.size() / 3);
    for (size_t p = 0; p < revealed.size(); ++p)
        for (size_t c = 0; c < 3; ++c)
            revealed[p] = revealed[p] || std::abs(full[p * 3 + c] - culled[p * 3 + c]) > 0.01f;
    return revealed;
}

RegionPsnr region_psnr(const std::vector<float>& image, const std::vector<float>& truth,
                       const std::vector<bool>& revealed)
{
    double sum[2] = { 0.0, 0.0 };
    size_t count[2] = { 0, 0 };
    for (size_t p = 0; p < revealed.size(); ++p) {
        const int region = revealed[p] ? 1 : 0;
        for (size_t c = 0; c < 3; ++c) {
            const double d = double(image[p * 3 + c]) - truth[p * 3 + c];
            sum[region] += d * d;
        }
        count[region] += 3;
    }
    auto psnr = [](double squares, size_t n) {
        return n == 0 || squares <= 0.0 ? INFINITY : 10.0 * std::log10(double(n) / squares);
    };
    return { psnr(sum[0], count[0]), psnr(sum[1], count[1]),
             psnr(sum[0] + sum[1], count[0] + count[1]),
             revealed.empty() ? 0.0 : double(count[1] / 3) / double(revealed.size()) };
}

bool split_scene(const std::string& scene, const std::string& truth, const std::string& work,
                 const Render& render, SceneSplit& split, std::string& error)
{
    const std::string culled = work + "/culled_layers.exr";
    if (!cull_hidden(scene + "/layers.exr", culled, error))
        return false;
    ImageBuf truth_image(truth);
    if (!truth_image.read(0, 0, true, TypeFloat)) {
        error = truth + ": " + truth_image.geterror();
        return false;
    }
    int renders = 0;
    auto rendered = [&](const std::string& input, std::vector<float>& pixels) {
        const std::string out = work + "/split_" + std::to_string(renders++) + ".exr";
        // Read past ImageBuf's cache, which would keep the pixels of a file
        // an earlier split wrote under the same name.
        std::unique_ptr<ImageInput> file;
        if (!render(input, out) || !(file = ImageInput::open(out))) {
            error = input + ": not rendered into " + out;
            return false;
        }
        ImageSpec spec = file->spec();
        spec.set_format(TypeFloat);
        ImageBuf image(spec);
        if (!file->read_image(0, 0, 0, spec.nchannels, TypeFloat, image.localpixels())) {
            error = out + ": " + file->geterror();
            return false;
        }
        pixels = display_srgb(image, &truth_image);
        return true;
    };
    std::vector<float> layers, culled_pixels, flat, deep;
    if (!rendered(scene + "/layers.exr", layers) || !rendered(culled, culled_pixels)
        || !rendered(scene + "/flat.exr", flat) || !rendered(scene + "/deep.exr", deep))
        return false;
    const std::vector<float> truth_pixels = display_srgb(truth_image);
    const std::vector<bool> revealed = revealed_pixels(layers, culled_pixels);
    split = { region_psnr(layers, truth_pixels, revealed), region_psnr(flat, truth_pixels, revealed),
              region_psnr(deep, truth_pixels, revealed) };
    return true;
}

}  // namespace defocus_fidelity
