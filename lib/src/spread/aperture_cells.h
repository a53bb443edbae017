// Internal: the aperture cut into cells, for compositing the layers once per
// part of the aperture (sub-aperture compositing): a near object hides
// different parts of what lies behind it from different points of the lens.
#pragma once

#include <vector>

#include <defocus/spread/aperture_profile.h>

namespace defocus {

/// One cell of a grid over the aperture's bounding square, clipped to the
/// aperture's shape, as a rectangle at unit CoC radius: through it, a pixel
/// at s of signed radius ρ (negative in front of the focus) lights
/// s + ρ·([u0, u1] × [v0, v1]), so that near and far points shift opposite
/// ways for the same part of the lens. A cell the shape cuts is the
/// rectangle of the shape's mean chord there and of the part's exact area.
/// `weight` is its share of the aperture's area.
struct ApertureCell {
    double u0, u1, v0, v1;
    double weight;
    int grid;  ///< its place in the grid, row after row
};

/// The cells of a grid of `across` × `across` over the bounding square of
/// the shape of `profile`, those the shape meets. Their weights add up to 1.
std::vector<ApertureCell> cut_aperture(const RowProfile& profile, int across);

/// The shares of `cells` (cut_aperture(profile, across)) in `clipped`, the
/// same shape clipped (ClippedProfile: the barrel's cat's eye): each cell's
/// area within it, over all of theirs. They add up to 1. A cell keeps its
/// rectangle, so a cell the clip cuts is taken as its clipped share spread
/// over all of it: finer cells follow the clip's edge closer.
std::vector<double> clipped_shares(const RowProfile& clipped,
                                   const std::vector<ApertureCell>& cells, int across);

}  // namespace defocus
