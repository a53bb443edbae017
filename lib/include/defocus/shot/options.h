// A shot's option types, each read by one stage: values only, so that the
// settings need none of the stages that use them.
#pragma once

#include <string>
#include <vector>

#include <defocus/optics/aperture.h>
#include <defocus/shot/memory_limit.h>

namespace defocus {

/// How each layer is spread: the aperture, and by which method.
struct SpreadOptions {
    Aperture aperture;
    /// Shapes (disc, polygon, mask) spread exactly, every pixel on its own
    /// (spread_scanline), rather than in bounded time (spread_aperture).
    bool exact_shape = false;
    /// The hybrid method's PSF image ("" = off): the pixels whose bokeh is
    /// visible (see visible_bokeh, with hybrid_threshold) are spread with
    /// it, the others with the aperture's fast filter.
    std::string psf_image;
    double hybrid_threshold = 4.0;
    /// Sub-aperture compositing: the aperture is cut into about this many
    /// cells, and where a near layer hides different parts of a far one
    /// from different points of the lens, the layers are composited within
    /// each cell and the cells added (composite/sub_aperture.h). 1 = one
    /// composite of the whole aperture (the layered model of compositing
    /// tools, faster); 0 = as many as each place needs.
    int aperture_cells = 0;
};

/// How the readers take the input files.
struct ReadOptions {
    /// The view of a multi-view file ("" = the first part's view).
    std::string view;
    /// The channel prefix to read colour and depth from, e.g. "beauty" for
    /// beauty.R..beauty.Z or Blender's "ViewLayer" for
    /// ViewLayer.Combined.R..ViewLayer.Depth.Z ("" = plain R,G,B,A,Z, or
    /// the one prefixed set the file has).
    std::string layer;
    /// Metres per depth unit: Z (and a deep sample's Z back) is multiplied
    /// by it as it is read, e.g. 0.01 for renders with Z in centimetres.
    double depth_scale = 1.0;
    /// Where the depth is when the input has no Z (or another one is
    /// wanted): a channel of the input by name, or else a depth image file
    /// (its Z channel, or its only channel) over the same display window
    /// ("" = the input's Z).
    std::string depth;
    /// Data channels to read beside colour and depth, into each layer's
    /// `data`, where its part has them (see composite/data_channels.h).
    std::vector<std::string> data_channels;
    /// What a file may ask to allocate (the shot's --memory-limit).
    MemoryLimit memory_limit;
    /// What an error tells the user to do for a file of colour without
    /// depth ("": give it with --depth, as for an input).
    std::string missing_depth_remedy;
};

/// How flat renders and deep images are cut into depth layers.
struct LayeringOptions {
    /// Number of depth layers; 0 chooses boundaries automatically so that
    /// no layer spans more than `max_coc_span` pixels of CoC.
    int layers = 0;
    double max_coc_span = 24.0;
    /// Width in pixels of CoC of the band around each boundary in which
    /// content belongs to both neighbouring layers (0: hard slicing).
    double soft_band = 1.5;
    /// What the layers cut may take (the shot's --memory-limit).
    MemoryLimit memory_limit;
};

/// What lies beyond the frame's data window when a blur reaches past it.
enum class EdgeMode {
    Auto,    ///< extend where the data window does not cover the blur's reach
    Extend,  ///< the edge pixels continue outwards
    Black,   ///< nothing: light fades towards the edges of the data window
};

/// "auto", "extend" or "black"; false for any other name.
bool parse_edge_mode(const std::string& name, EdgeMode& mode);
const char* edge_mode_name(EdgeMode mode);

/// What a sequence does about frames whose input files are missing.
enum class MissingFrames {
    Error,  ///< refuse the shot, naming the missing frames
    Skip,   ///< render only the frames whose inputs are there
    Hold,   ///< a missing frame reads the nearest earlier frame's inputs
};

/// "error", "skip" or "hold"; false for any other name.
bool parse_missing_frames(const std::string& name, MissingFrames& missing);
const char* missing_frames_name(MissingFrames missing);

/// The data window of a result.
enum class OutputWindow {
    Input,    ///< the input's data window, as oiiotool's filters keep it
    Display,  ///< the display window
    Grown,    ///< the input's data window grown by the blur: all of the light
};

/// "input", "display" or "grown"; false for any other name.
bool parse_output_window(const std::string& name, OutputWindow& window);
const char* output_window_name(OutputWindow window);

/// Extra channels written beside the image.
enum class Aov {
    None,
    /// "confidence": the fraction of each pixel's light that came from
    /// rebuilt surfaces (Layer::rebuilt), 0 where all of it was seen; then
    /// that fraction split by how they were rebuilt.
    Confidence,
    /// "coc": the signed CoC diameter of the front-most layer that reaches
    /// each pixel (see coc_aov), to drive other blurs from.
    Coc,
};
bool parse_aov(const std::string& name, Aov& aov);
const char* aov_name(Aov aov);
/// The channels `aov` adds, in order: none; "confidence" and its shares
/// by method (RebuiltBy) "confidence.continued", "confidence.lines",
/// "confidence.patterns" and "confidence.smooth"; "coc".
const std::vector<std::string>& aov_channel_names(Aov aov);

/// How a data channel read from the input is carried through defocus
/// (composite/data_channels.h).
enum class DataKind {
    Id,        ///< the ID with the largest share of the pixel
    Dominant,  ///< the value of the layer with the largest share (P, N)
    Average,   ///< the coverage-weighted mean
};

const char* data_kind_name(DataKind kind);

/// One entry of the data channels setting: "auto", or a channel and how it
/// is carried.
struct DataChannelEntry {
    bool automatic = false;
    std::string name;
    DataKind kind = DataKind::Dominant;
};

/// Reads the data channels setting: "none", or a comma-separated list of
/// "auto" and channel names, each optionally followed by ":id",
/// ":dominant" (the default) or ":average". False with `error` naming
/// `label`.
bool parse_data_channels(const std::string& label, const std::string& setting,
                         std::vector<DataChannelEntry>& entries, std::string& error);

}  // namespace defocus
