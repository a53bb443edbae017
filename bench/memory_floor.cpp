#include "memory_floor.h"

#include <algorithm>

#include <OpenImageIO/parallel.h>
#include <OpenImageIO/timer.h>

namespace bench {

namespace {

/// Rows split over every thread (OIIO's default makes tasks of at least
/// 1024 items, so two at most for these rows), as the library does.
const OIIO::paropt by_rows = OIIO::paropt(0).minitems(1);

}  // namespace

std::vector<FloorLayer> make_floor_layers()
{
    const int width = 4096, height = 2160;
    // Coverage and CoC diameter of each layer at (x, y); < 0 coverage: empty.
    using Shape = float (*)(int x, int y, float& coc);
    const Shape shapes[4] = {
        [](int, int, float& coc) { coc = 60.0f; return 1.0f; },
        [](int, int y, float& coc) {
            coc = 10.0f + 30.0f * float(y - 1080) / 1080.0f;
            return y >= 1080 ? 1.0f : 0.0f;
        },
        [](int x, int, float& coc) {
            coc = 0.0f;
            return x >= 1843 && x < 2253 ? 1.0f : 0.0f;
        },
        [](int x, int y, float& coc) {
            coc = -100.0f;
            return x < 2048 && y < 1080 ? 1.0f : 0.0f;
        },
    };
    std::vector<FloorLayer> layers(4);
    for (int i = 0; i < 4; ++i) {
        FloorLayer& l = layers[i];
        l.width = width;
        l.height = height;
        l.color.assign(size_t(width) * height * 4, 0.0f);
        l.coc.assign(size_t(width) * height, 0.0f);
        OIIO::parallel_for(0, height, [&](int y) {
            unsigned state = unsigned(y * 7919 + i * 104729);
            for (int x = 0; x < width; ++x) {
                const size_t p = size_t(y) * width + x;
                const float cover = shapes[i](x, y, l.coc[p]);
                for (int c = 0; c < 3; ++c) {
                    state = state * 1664525u + 1013904223u;
                    l.color[p * 4 + c] = cover * (0.01f + 10.0f * float(state >> 8) * 0x1p-24f);
                }
                l.color[p * 4 + 3] = cover;
            }
        }, by_rows);
    }
    return layers;
}

double memory_floor(const std::vector<FloorLayer>& layers)
{
    // One accumulator, written before timing: fresh pages cost the kernel
    // time that a program reusing its buffers does not pay.
    size_t largest = 0;
    for (const FloorLayer& l : layers)
        largest = std::max(largest, size_t(l.width) * l.height * 4);
    std::vector<float> sums(largest, 0.0f);
    OIIO::Timer timer;
    float keep = 0.0f;
    for (const FloorLayer& l : layers) {
        // Down the columns: read the layer once, read and write the sums.
        OIIO::parallel_for(0, l.height, [&](int y) {
            const float* color = &l.color[size_t(y) * l.width * 4];
            const float* coc = &l.coc[size_t(y) * l.width];
            float* row = &sums[size_t(y) * l.width * 4];
            for (int x = 0; x < l.width; ++x)
                for (int c = 0; c < 4; ++c)
                    row[x * 4 + c] += color[x * 4 + c] * coc[x];
        }, by_rows);
        // Along the rows: read and write the sums again.
        OIIO::parallel_for(0, l.height, [&](int y) {
            float* row = &sums[size_t(y) * l.width * 4];
            for (int x = 1; x < l.width; ++x)
                for (int c = 0; c < 4; ++c)
                    row[x * 4 + c] += row[x * 4 + c - 4];
        }, by_rows);
        keep += sums[sums.size() / 2];
    }
    const double elapsed = timer();
    // Keeps the work from being optimised away.
    asm volatile("" : : "r"(&keep) : "memory");
    return elapsed;
}

}  // namespace bench
