// Internal: a deep volume sample (Z back beyond Z) as a uniform medium.
#pragma once

#include <algorithm>
#include <cmath>

#include <defocus/scene.h>

namespace defocus {

/// OpenEXR's deep-pixel rules take a volume sample as a uniform medium
/// between its front and back, whose alpha 1 - e^(-τ) is that of its
/// whole optical depth τ. Layering cuts it by CoC, and at a pixel the CoC
/// is affine in 1/z: so depths between the ends go by fractions of 1/z.
struct DeepVolume {
    explicit DeepVolume(const DeepSample& s)
        : density(-std::log1p(-std::min(double(s.a), 1.0 - 1e-7)) / (double(s.zback) - s.z))
        , inv_near(1.0 / s.z)
        , inv_far(1.0 / s.zback)
    {
    }

    /// The depth at fraction t of the way from the front (0) to the back
    /// (1) in 1/z, and so in CoC.
    double depth_at(double t) const { return 1.0 / (inv_near + (inv_far - inv_near) * t); }

    double density;  ///< optical depth per unit of depth
    double inv_near, inv_far;
};

}  // namespace defocus
