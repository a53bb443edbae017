// Internal: magnification about a centre along one axis of a frame, as
// lateral chromatic aberration magnifies red and blue.
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace defocus {

/// Magnification by m about o along one axis of the frame, for each output
/// pixel i of a range: where it comes from (the source pixel below that
/// and the fraction past it), and the source pixels whose light lands
/// within a pixel of it, with the weight each lands with there. The same
/// for every row (or column), so taken once.
class MagnifiedAxis {
public:
    struct Pixel {
        int from;
        double fraction;
        int first_source, sources;
        size_t weights;  ///< where its sources' weights start
    };

    MagnifiedAxis(int begin, int end, double m, double o) : m_begin(begin)
    {
        for (int i = begin; i < end; ++i) {
            const double from = comes(i, m, o);
            Pixel p { int(std::floor(from)), 0.0, int(std::ceil(comes(i - 1, m, o))), 0,
                      m_weights.size() };
            p.fraction = from - p.from;
            p.sources = std::max(0, int(std::floor(comes(i + 1, m, o))) - p.first_source + 1);
            for (int k = 0; k < p.sources; ++k)
                m_weights.push_back(1.0 - std::abs(lands(p.first_source + k, m, o) - i));
            m_pixels.push_back(p);
        }
    }
    /// The output pixels that the light and the coverage of source pixels
    /// [begin, end) can reach, with a pixel to spare.
    static std::pair<int, int> reached(int begin, int end, double m, double o)
    {
        return { int(std::floor(lands(begin, m, o))) - 2, int(std::ceil(lands(end, m, o))) + 2 };
    }

    const Pixel& operator[](int i) const { return m_pixels[size_t(i - m_begin)]; }
    double weight(const Pixel& p, int k) const { return m_weights[p.weights + size_t(k)]; }

private:
    // Pixel indices, centres at i + 1/2: where source pixel i lands, and
    // where output pixel i comes from.
    static double lands(double i, double m, double o) { return o + (i + 0.5 - o) * m - 0.5; }
    static double comes(double i, double m, double o) { return o + (i + 0.5 - o) / m - 0.5; }

    int m_begin;
    std::vector<Pixel> m_pixels;
    std::vector<double> m_weights;
};

}  // namespace defocus
