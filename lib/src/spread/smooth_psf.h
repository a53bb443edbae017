// Internal: the smooth PSFs of tent and smooth spreading, order-n boxes
// (see spread_smooth.cpp): their widths for a CoC radius, and the four
// separable pieces a pixel is spread as.
#pragma once

namespace defocus {

/// The two integer box widths whose blend gives the PSF of CoC radius r,
/// and the blend. The order-n box of width w has variance n(w² - 1)/12;
/// matching the CoC disc's r²/4 gives w² = 1 + 3r²/n. Odd orders need odd
/// widths to stay centred.
struct Widths {
    int w[2];
    double weight[2];
};

Widths smooth_widths(int order, double r);

/// The binomial coefficient C(n, k).
int binomial(int n, int k);

/// The half-width of the order-n box of width w: n(w - 1)/2.
inline int half_support(int order, int w) { return order * (w - 1) / 2; }

/// How a pixel of one radius is spread: its two widths and the amplitude
/// of each of its four separable pieces (x width a, y width b) per unit of
/// value, 0 for a piece of no weight.
struct SmoothPieces {
    Widths ws;
    double scale[2][2];

    SmoothPieces(int order, double r)
        : ws(smooth_widths(order, r))
    {
        for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b) {
                double power = 1.0;  // (w_a w_b)^order, exact
                for (int k = 0; k < order; ++k)
                    power *= double(ws.w[a]) * double(ws.w[b]);
                scale[a][b] = ws.weight[a] * ws.weight[b] / power;
            }
    }
};

}  // namespace defocus
