// Internal: which pixels the Bounded method spreads alone rather than in
// merged blocks.
#pragma once

#include <cstdint>
#include <vector>

#include "spread/spread_engine.h"

namespace defocus {

/// Adds to `kept` (one byte a pixel of source.roi, 1 for the pixels kept
/// exact: highlights, see visible_bokeh) every lit pixel whose block at its
/// level holds one of them, for the levels whose blocks spread a uniform
/// block's exact footprint.
///
/// A block spreads its light as if even over the whole block, so a block
/// that a highlight leaves a hole in would move light into it, and beside
/// highlights the merged and the lone footprints would no longer add up to
/// an even surface (an opaque card in a layer, whose corners pass the
/// highlight test, came out 0.4% see-through 14 pixels inside its edge).
void add_pixels_alone(const SpreadSource& source, std::vector<uint8_t>& kept, int nthreads);

}  // namespace defocus
