// Data channels that survive defocus: depth, IDs, cryptomatte, position and
// normals, which averaging as colour would break.
//
// Once the layers and their alphas are fixed, spreading and compositing
// are linear in colour: a quantity q spread as premultiplied colour (q
// times alpha) through the same layers composites to the alpha-weighted
// mean of q over what each output pixel shows. Each kind of channel is
// made from such spreads:
//  - depth: the coverage-weighted mean ("Z") and that of the front-most
//    layer reaching the pixel ("ZFront");
//  - P, N and other "dominant" channels: the value of the layer with the
//    largest share of the pixel's alpha (its coverage-weighted mean over
//    that layer's pixels), normals made unit length again;
//  - IDs: each ID's share of the output alpha, spread as a matte; the
//    pixel takes the ID with the largest share, never a mix;
//  - cryptomatte: each object's matte (its rank coverages, normalised to
//    the source pixel's alpha) spread and composited: its share of the
//    output alpha, attenuated by what lies in front of it. The largest
//    shares are written back as rank/coverage pairs, so that a decoded
//    matte is the object's share of the output alpha.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <defocus/composite/defocus_layers.h>
#include <defocus/layers/layered_scene.h>
#include <defocus/shot/options.h>

namespace defocus {

struct DataChannel {
    std::string name;
    DataKind kind;
    bool normal = false;  ///< one of a normal's three: made unit length again
};

/// A cryptomatte layer set (`CryptoObject00.R` ...): its channels in rank
/// order, each rank an ID (float bits of a hash) and a coverage.
struct CryptoSet {
    std::string name;                   ///< e.g. CryptoObject
    std::vector<std::string> channels;  ///< name00.R, name00.G, ... : id, coverage, id, ...

    int ranks() const { return int(channels.size()) / 2; }
};

/// The data channels a shot carries, chosen from the input's channel names.
struct DataPlan {
    bool depth = false;  ///< writes Z and ZFront from the layers' depth
    std::vector<DataChannel> channels;
    std::vector<CryptoSet> crypto;

    bool empty() const { return !depth && channels.empty() && crypto.empty(); }
    /// The input channels to read into each layer's `data`.
    std::vector<std::string> input_channels() const;
    /// The channels data_channels() makes, in order.
    std::vector<std::string> output_channels() const;
    /// Whether each channel output_channels() names is a name of its own,
    /// beside the colour's and the channels of the AOV `aov`: a second
    /// channel of a name is written as "channelN". Else false with `error`
    /// naming both.
    bool distinct_names(Aov aov, std::string& error) const;
    /// What is carried and as what, for -v ("" for nothing).
    std::string summary() const;
};

/// The data channels `setting` names among the channels of `input` (the
/// scene's header): "none"; "auto", every channel whose name says it is
/// data (cryptomatte sets, by their metadata or `[prefix.]Crypto*NN.R`; IDs such as
/// `id`, `objectId`, `IndexOB`; P, N, Position and Normal sets), with the
/// depth; or channel names, with their kinds (parse_data_channels()).
/// False with `error` for a named channel the input lacks.
bool plan_data_channels(const OIIO::ImageSpec& input, const std::string& setting,
                        DataPlan& plan, std::string& error);

/// The channels of `plan` over `roi`, for `result`: the scene's defocused
/// RGBA over `roi` as defocus_layers() made it, spread as `spread` says
/// (less chromatic aberration and the PSF image, which change colour, not
/// reach). Cryptomatte coverages are scaled so that they sum, with the
/// pixel's share of unlabelled light, to the result's alpha.
/// `keep_going`, where given, is asked before each spread with how many of
/// the stage's spreads are done and how many there are (thousands of IDs
/// are hundreds of spreads); false stops with the error "cancelled".
bool data_channels(OIIO::ImageBuf& dst, const OIIO::ImageBuf& result, const LayeredScene& scene,
                   const Camera& camera, const SpreadOptions& spread,
                   const ApertureImages& images, OutputWindow window, const DataPlan& plan,
                   int nthreads = 0,
                   const std::function<bool(int done, int total)>& keep_going = {});

}  // namespace defocus
