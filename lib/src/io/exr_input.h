// Internal: OpenEXR pixels read once, straight into the layers' buffers.
//
// OpenImageIO 2.4 crashes or hangs on some corrupt EXRs, so every file used
// to be checked first with OpenEXR's checkOpenEXRFile, which decodes every
// pixel through several of OpenEXR's interfaces: each input was decoded
// two or three times. Here the one decode is also the check. Flat parts go
// through OpenEXR's core library, which validates every header field, offset
// and chunk it reads (the checker's own core pass: it finds damage the C++
// interfaces read as valid); deep parts through the C++ interface, with
// exceptions caught and the checker's memory guards.
#pragma once

#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include <defocus/scene.h>
#include <defocus/shot/memory_limit.h>

namespace defocus {

/// Whether a file starts as an OpenEXR file does (its magic number).
bool is_openexr_file(const std::string& filename);

/// Where one channel of a part is decoded to, as float: the address of the
/// part's data window origin, and the steps to the next pixel and row.
struct ChannelTarget {
    std::string channel;
    float* origin;
    size_t pixel_stride, row_stride;  ///< in floats
};

class ExrInput {
public:
    ExrInput() = default;
    ExrInput(const ExrInput&) = delete;
    ExrInput& operator=(const ExrInput&) = delete;
    ~ExrInput();

    /// Opens a file and checks its headers; false with `error` ("corrupt or
    /// truncated OpenEXR file: ...", or a chunk whose decoding buffers the
    /// memory limit does not allow).
    bool open(const std::string& filename, std::string& error,
              const MemoryLimit& limit = MemoryLimit());
    bool is_open() const { return m_context != nullptr; }

    /// The string attribute `name` of the first part, or "" when it has
    /// none of that name and type.
    std::string string_attribute(const char* name) const;

    /// Whether every chunk of every part (every tile of every level) is in
    /// the file whole: its offset in the chunk table and its data within
    /// the file, as a finished write leaves them. A file cut short, or one
    /// whose writer died before filling in its chunk table, is not. False
    /// with `why`.
    bool complete(std::string& why) const;

    /// Decodes the named channels of flat part `part` (scanline or tiled,
    /// its full-resolution level) into their targets, laid out over
    /// `window`, chunks in parallel. False with `error` when a chunk is
    /// damaged, or when the part's data window or channels are not those
    /// the targets were laid out for (another reader of the same headers,
    /// such as OpenImageIO's, read them differently).
    bool read(int part, const OIIO::ROI& window, const std::vector<ChannelTarget>& targets,
              std::string& error, int nthreads) const;

private:
    struct Context;
    Context* m_context = nullptr;
};

/// The channels of a deep part that make a layer: colour, depth and, when
/// the part has one, the back of each sample's depth interval.
struct DeepChannels {
    std::string color[4], depth, depth_back;
    std::vector<std::string> data;  ///< data channels, into DeepImage::data
};

/// Bytes of a deep part's per-pixel tables over a data window of
/// `width` x `height`, before its samples.
double deep_table_bytes(int64_t width, int64_t height);

/// Reads deep part `part` (scanline or tiled) of an OpenEXR file, with
/// every sample's RGBA, Z and ZBack (ZBack = Z without one), and its data
/// channels. False with
/// `error` when the file is damaged, or would need more memory than
/// `limit` (checked on the data window, then on the sample counts, before
/// either is allocated).
bool read_deep_part(const std::string& filename, int part, const DeepChannels& channels,
                    const MemoryLimit& limit, DeepImage& image, std::string& error);

}  // namespace defocus
