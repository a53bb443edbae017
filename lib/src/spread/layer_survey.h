// Internal: the one pass over a layer that decides how each pixel is
// spread, and sums the pixels spread in blocks.
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "spread/item_rows.h"
#include "spread/spread_engine.h"

namespace defocus {

/// What one pass over a layer finds: the largest radius on the dense path
/// and on each sparse level, and the sparse levels' block rows, summed.
struct LayerSurvey {
    float dense_max = -1.0f;
    std::vector<uint8_t> dense_rows;  ///< per source row: any pixel on the dense path
    std::vector<float> sparse_max;
    std::vector<std::vector<ItemRow>> block_rows;  ///< per level, per block row
};

/// Surveys source rows [y0, y1), which hold whole block rows of every
/// level: each pixel's components once, dense ones noted, sparse ones
/// summed into their level's blocks, each block on the footprints of its
/// centre (see ShapePrograms).
void survey_rows(const SpreadSource& source, SpreadMethod method, const ShapePrograms* shape,
                 const std::vector<std::unique_ptr<SpreadEngine::Sparse>>& levels, int y0, int y1,
                 LayerSurvey& found, std::mutex& merge);

}  // namespace defocus
