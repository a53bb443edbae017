#include "io/exr_input.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <set>

#include <OpenEXR/ImfArray.h>
#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepScanLineInputPart.h>
#include <OpenEXR/ImfDeepTiledInputPart.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/openexr.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include "io/exr_zip.h"

namespace defocus {

using OIIO::Strutil::fmt::format;

namespace {

/// The core library reports errors through a callback: keep the last
/// message of this thread instead of printing it.
thread_local std::string core_message;

void keep_message(exr_const_context_t, int code, const char* message)
{
    core_message = format("{} ({})", message ? message : "", exr_get_error_code_as_string(code));
}

/// The address OpenEXR's frame buffers want: that of pixel (0, 0) for an
/// array holding the data window from `origin` elements on, computed in
/// integers since it may lie outside the array.
template<typename T>
char* frame_base(T* data, size_t origin)
{
    return reinterpret_cast<char*>(reinterpret_cast<intptr_t>(data)
                                   - intptr_t(origin * sizeof(T)));
}

std::string damaged(const std::string& filename, const std::string& why)
{
    return format("{}: corrupt or truncated OpenEXR file: {}", filename,
                  why.empty() ? "unreadable" : why);
}

/// Reads the attribute headers of an OpenEXR file as they lie in it (name,
/// type, 4-byte size, value; a header ends with an empty name, and a
/// multi-part file's headers with an empty header) and checks that every
/// value fits in the file and no name is given twice (OpenEXR's libraries
/// differ on which one counts). OpenEXR's C++ interface (OpenImageIO's reader,
/// the deep reader) allocates an attribute's declared size before reading
/// it: a 4 KB file declaring a 1.9 GB string took 1.9 GB and 4 s.
bool attributes_fit(const std::string& filename, std::string& why)
{
    FILE* f = OIIO::Filesystem::fopen(filename, "rb");
    if (!f) {
        why = "cannot open";
        return false;
    }
    const uint64_t file_bytes = OIIO::Filesystem::file_size(filename);
    auto read_name = [&](std::string& name) {
        name.clear();
        for (int c; (c = std::fgetc(f)) > 0 && name.size() < 256;)
            name += char(c);
        return !std::ferror(f) && !std::feof(f);
    };
    unsigned char start[8];
    bool ok = std::fread(start, 1, 8, f) == 8;
    const bool multipart = start[5] & 0x10;  // version flags bit 12
    for (bool more = ok; more;) {
        std::string name, type;
        std::set<std::string> names;
        while (ok && (ok = read_name(name)) && !name.empty()) {
            if (!names.insert(name).second) {
                why = format("attribute '{}' is given twice in one header", name);
                std::fclose(f);
                return false;
            }
            int32_t size = 0;
            ok = read_name(type) && std::fread(&size, 4, 1, f) == 1;
            const uint64_t at = uint64_t(std::ftell(f));
            if (ok && (size < 0 || at + uint64_t(size) > file_bytes)) {
                why = format("attribute '{}' declares {} bytes, past the end of the file",
                             name, size);
                std::fclose(f);
                return false;
            }
            ok = ok && std::fseek(f, size, SEEK_CUR) == 0;
        }
        // Another header follows unless the next byte ends the list.
        const int next = multipart && ok ? std::fgetc(f) : 0;
        more = next > 0 && std::ungetc(next, f) != EOF;
    }
    std::fclose(f);
    if (!ok)
        why = "its headers end early";
    return ok;
}

/// The pixels of one chunk of `part`: a block of scanlines or a tile.
int64_t chunk_pixels(exr_const_context_t file, int part, exr_storage_t storage)
{
    if (storage == EXR_STORAGE_SCANLINE || storage == EXR_STORAGE_DEEP_SCANLINE) {
        exr_attr_box2i_t window {};
        int32_t lines = 0;
        exr_get_data_window(file, part, &window);
        exr_get_scanlines_per_chunk(file, part, &lines);
        return (int64_t(window.max.x) - window.min.x + 1) * std::max(lines, 1);
    }
    uint32_t width = 0, height = 0;
    exr_tile_level_mode_t level;
    exr_tile_round_mode_t round;
    exr_get_tile_descriptor(file, part, &width, &height, &level, &round);
    return int64_t(width) * int64_t(height);
}

/// The bytes of one pixel of `part`'s channels, as stored.
double pixel_bytes(exr_const_context_t file, int part)
{
    const exr_attr_chlist_t* channels = nullptr;
    double bytes = 0.0;
    if (exr_get_channels(file, part, &channels) == EXR_ERR_SUCCESS && channels)
        for (int c = 0; c < channels->num_channels; ++c)
            bytes += channels->entries[c].pixel_type == EXR_PIXEL_HALF ? 2.0 : 4.0;
    return bytes;
}

/// Whether OpenEXR's C++ interface can open `part` at the cost its chunks
/// declare; false with `why`. A flat part's chunk (one block of scanlines or
/// a tile) is decoded into a buffer per reading thread, allocated when the
/// part is opened, and its decompressor takes another, whatever the file
/// holds: their bytes are added to `buffer_bytes`. A deep part's chunk has
/// its table of sample counts sized in an int in OpenEXR 3.1: one counting
/// more than 2^31 bytes' worth of pixels (a data window 738 million pixels
/// wide, found by fuzzing) had it allocate a negative size.
bool chunks_openable(exr_const_context_t file, int part, double& buffer_bytes, std::string& why)
{
    exr_storage_t storage = EXR_STORAGE_SCANLINE;
    if (exr_get_storage(file, part, &storage) != EXR_ERR_SUCCESS) {
        why = core_message;
        return false;
    }
    const int64_t pixels = chunk_pixels(file, part, storage);
    if (storage == EXR_STORAGE_SCANLINE || storage == EXR_STORAGE_TILED) {
        buffer_bytes += 2.0 * double(pixels) * pixel_bytes(file, part);
        return true;
    }
    if (pixels * int64_t(sizeof(unsigned)) > INT32_MAX) {
        why = format("part {}'s deep chunks hold {} pixels each, more than OpenEXR can count",
                     part, pixels);
        return false;
    }
    return true;
}

}  // namespace

bool is_openexr_file(const std::string& filename)
{
    unsigned char magic[4] = { 0, 0, 0, 0 };
    if (FILE* f = OIIO::Filesystem::fopen(filename, "rb")) {
        const size_t n = std::fread(magic, 1, 4, f);
        std::fclose(f);
        return n == 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31
               && magic[3] == 0x01;
    }
    return false;
}

double deep_table_bytes(int64_t width, int64_t height)
{
    // A sample count, a pointer per channel to the pixel's first sample
    // (up to six channels), and the pixel's offset in the image read.
    return double(width) * double(height)
           * (sizeof(unsigned) + 6 * sizeof(float*) + sizeof(size_t));
}

struct ExrInput::Context {
    exr_context_t file = nullptr;
    std::string filename;
};

ExrInput::~ExrInput()
{
    if (m_context) {
        exr_finish(&m_context->file);
        delete m_context;
    }
}

bool ExrInput::open(const std::string& filename, std::string& error, const MemoryLimit& limit)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = keep_message;
    core_message.clear();
    exr_context_t file = nullptr;
    if (exr_start_read(&file, filename.c_str(), &init) != EXR_ERR_SUCCESS) {
        exr_finish(&file);
        error = damaged(filename, core_message);
        return false;
    }
    std::string why;
    if (!attributes_fit(filename, why)) {
        exr_finish(&file);
        error = damaged(filename, why);
        return false;
    }
    // Every chunk has an 8-byte offset in the file's tables. OpenEXR's C++
    // interface (OpenImageIO's reader, the deep reader) allocates the tables
    // before it finds the file too short: a 4 KB file claiming a giant data
    // window cost 1.9 GB and 4 s.
    int parts = 0;
    uint64_t table_bytes = 0;
    double buffer_bytes = 0.0;
    exr_get_count(file, &parts);
    for (int part = 0; part < parts; ++part) {
        int32_t chunks = 0;
        if (exr_get_chunk_count(file, part, &chunks) != EXR_ERR_SUCCESS || chunks < 0) {
            exr_finish(&file);
            error = damaged(filename, core_message);
            return false;
        }
        table_bytes += uint64_t(chunks) * sizeof(uint64_t);
        // Buffers counted over all parts: a reader opens every one of them.
        if (!chunks_openable(file, part, buffer_bytes, why)) {
            exr_finish(&file);
            error = damaged(filename, why);
            return false;
        }
    }
    const uint64_t file_bytes = OIIO::Filesystem::file_size(filename);
    if (table_bytes > file_bytes) {
        exr_finish(&file);
        error = damaged(filename, format("its chunk tables take {} bytes, the file {}",
                                         table_bytes, file_bytes));
        return false;
    }
    // Against the whole limit, not what the frame leaves of it: the flat
    // reader decodes through the core library and never fills these
    // buffers, so they are address space more than memory; but a header
    // that asks for more than the whole limit is refused before they are
    // made (under ASan, 3.2 GB of them took seconds).
    const MemoryLimit whole(limit.bytes());
    if (!whole.allows(buffer_bytes)) {
        exr_finish(&file);
        error = format("{}: {}", filename,
                       whole.exceeded(parts > 1 ? "decoding one chunk of each part"
                                                : "decoding one chunk",
                                      buffer_bytes));
        return false;
    }
    m_context = new Context { file, filename };
    return true;
}

std::string ExrInput::string_attribute(const char* name) const
{
    int32_t length = 0;
    const char* text = nullptr;
    if (exr_attr_get_string(m_context->file, 0, name, &length, &text) != EXR_ERR_SUCCESS || !text
        || length < 0)
        return "";
    return std::string(text, size_t(length));
}

bool ExrInput::complete(std::string& why) const
{
    exr_const_context_t file = m_context->file;
    core_message.clear();
    int parts = 0;
    exr_get_count(file, &parts);
    for (int part = 0; part < parts; ++part) {
        exr_storage_t storage;
        exr_attr_box2i_t dw;
        if (exr_get_storage(file, part, &storage) != EXR_ERR_SUCCESS
            || exr_get_data_window(file, part, &dw) != EXR_ERR_SUCCESS) {
            why = core_message;
            return false;
        }
        exr_chunk_info_t chunk;
        if (storage == EXR_STORAGE_SCANLINE || storage == EXR_STORAGE_DEEP_SCANLINE) {
            int32_t lines = 1;
            if (exr_get_scanlines_per_chunk(file, part, &lines) != EXR_ERR_SUCCESS || lines < 1) {
                why = core_message;
                return false;
            }
            for (int64_t y = dw.min.y; y <= dw.max.y; y += lines)
                if (exr_read_scanline_chunk_info(file, part, int(y), &chunk) != EXR_ERR_SUCCESS) {
                    why = core_message;
                    return false;
                }
            continue;
        }
        uint32_t tile_w = 0, tile_h = 0;
        exr_tile_level_mode_t mode;
        exr_tile_round_mode_t round;
        int32_t levels_x = 0, levels_y = 0;
        if (exr_get_tile_descriptor(file, part, &tile_w, &tile_h, &mode, &round) != EXR_ERR_SUCCESS
            || exr_get_tile_levels(file, part, &levels_x, &levels_y) != EXR_ERR_SUCCESS) {
            why = core_message;
            return false;
        }
        for (int ly = 0; ly < levels_y; ++ly)
            for (int lx = 0; lx < levels_x; ++lx) {
                // Mipmaps have the levels of the diagonal only.
                if (mode != EXR_TILE_RIPMAP_LEVELS && lx != ly)
                    continue;
                int32_t width = 0, height = 0, tw = 0, th = 0;
                if (exr_get_level_sizes(file, part, lx, ly, &width, &height) != EXR_ERR_SUCCESS
                    || exr_get_tile_sizes(file, part, lx, ly, &tw, &th) != EXR_ERR_SUCCESS
                    || tw < 1 || th < 1) {
                    why = core_message;
                    return false;
                }
                const int32_t count_x = (width + tw - 1) / tw, count_y = (height + th - 1) / th;
                for (int ty = 0; ty < count_y; ++ty)
                    for (int tx = 0; tx < count_x; ++tx)
                        if (exr_read_tile_chunk_info(file, part, tx, ty, lx, ly, &chunk)
                            != EXR_ERR_SUCCESS) {
                            why = core_message;
                            return false;
                        }
            }
    }
    return true;
}

namespace {

/// A flat part's chunks, from its headers: scanline blocks, or tiles of
/// the top level.
struct FlatChunks {
    exr_storage_t storage;
    exr_attr_box2i_t dw;
    exr_compression_t compression;
    int64_t across = 1, count = 0;  ///< tiles across a row of them; chunks
    int32_t lines = 1;              ///< scanlines a chunk
    uint32_t tile_w = 0, tile_h = 0;

    /// Chunk c's first pixel.
    void origin(int64_t c, int64_t& x0, int64_t& y0) const
    {
        x0 = dw.min.x + (storage == EXR_STORAGE_SCANLINE ? 0 : (c % across) * tile_w);
        y0 = storage == EXR_STORAGE_SCANLINE ? dw.min.y + c * lines
                                             : dw.min.y + (c / across) * tile_h;
    }

    exr_result_t info(exr_const_context_t file, int part, int64_t c, exr_chunk_info_t& chunk) const
    {
        if (storage == EXR_STORAGE_SCANLINE)
            return exr_read_scanline_chunk_info(file, part, int(dw.min.y + c * lines), &chunk);
        return exr_read_tile_chunk_info(file, part, int(c % across), int(c / across), 0, 0,
                                        &chunk);
    }
};

/// Part `part`'s chunks, checked against the window and channels that
/// `targets` were laid out for. False with `error` when the headers are
/// damaged, read two ways, or the part is deep.
bool flat_chunks(exr_const_context_t file, const std::string& filename, int part,
                 const OIIO::ROI& window, const std::vector<ChannelTarget>& targets,
                 FlatChunks& out, std::string& error)
{
    exr_attr_box2i_t& dw = out.dw;
    if (exr_get_storage(file, part, &out.storage) != EXR_ERR_SUCCESS
        || exr_get_data_window(file, part, &dw) != EXR_ERR_SUCCESS
        || exr_get_compression(file, part, &out.compression) != EXR_ERR_SUCCESS) {
        error = damaged(filename, core_message);
        return false;
    }
    const int64_t width = int64_t(dw.max.x) - dw.min.x + 1, height = int64_t(dw.max.y) - dw.min.y + 1;
    // The core library decodes into buffers laid out by another reader:
    // where the two read a header differently (an attribute given twice),
    // a chunk would be written past them.
    const exr_attr_chlist_t* channels = nullptr;
    if (exr_get_channels(file, part, &channels) != EXR_ERR_SUCCESS) {
        error = damaged(filename, core_message);
        return false;
    }
    auto has_channel = [channels](const ChannelTarget& t) {
        return std::any_of(channels->entries, channels->entries + channels->num_channels,
                           [&](const exr_attr_chlist_entry_t& entry) {
                               return t.channel == entry.name.str;
                           });
    };
    if (dw.min.x != window.xbegin || dw.min.y != window.ybegin || width != window.width()
        || height != window.height() || !std::all_of(targets.begin(), targets.end(), has_channel)) {
        error = damaged(filename, format("part {}'s headers read two ways", part));
        return false;
    }
    if (out.storage == EXR_STORAGE_SCANLINE) {
        if (exr_get_scanlines_per_chunk(file, part, &out.lines) != EXR_ERR_SUCCESS
            || out.lines < 1) {
            error = damaged(filename, core_message);
            return false;
        }
        out.count = (height + out.lines - 1) / out.lines;
    } else if (out.storage == EXR_STORAGE_TILED) {
        exr_tile_level_mode_t mode;
        exr_tile_round_mode_t round;
        if (exr_get_tile_descriptor(file, part, &out.tile_w, &out.tile_h, &mode, &round)
                != EXR_ERR_SUCCESS
            || out.tile_w < 1 || out.tile_h < 1) {
            error = damaged(filename, core_message);
            return false;
        }
        out.across = (width + out.tile_w - 1) / out.tile_w;
        out.count = out.across * ((height + out.tile_h - 1) / out.tile_h);
    } else {
        error = format("{}: part {} is deep, not flat", filename, part);
        return false;
    }
    return true;
}

/// Points the decoder's channels that `targets` ask for at their place for
/// the chunk starting at (x0, y0), as float; the others are skipped. False
/// with `error` for a subsampled channel.
bool aim_channels(exr_decode_pipeline_t& decoder, const std::vector<ChannelTarget>& targets,
                  const exr_attr_box2i_t& dw, int64_t x0, int64_t y0,
                  const std::string& filename, std::string& error)
{
    for (int i = 0; i < decoder.channel_count; ++i) {
        exr_coding_channel_info_t& ch = decoder.channels[i];
        ch.decode_to_ptr = nullptr;  // channels that are not asked for are skipped
        for (const ChannelTarget& t : targets) {
            if (t.channel != ch.channel_name)
                continue;
            if (ch.x_samples != 1 || ch.y_samples != 1) {
                error = format("{}: channel {} is subsampled, which defocus does not read",
                               filename, t.channel);
                return false;
            }
            ch.user_data_type = EXR_PIXEL_FLOAT;
            ch.user_bytes_per_element = sizeof(float);
            ch.user_pixel_stride = int32_t(t.pixel_stride * sizeof(float));
            ch.user_line_stride = int32_t(t.row_stride * sizeof(float));
            ch.decode_to_ptr = reinterpret_cast<uint8_t*>(
                t.origin + size_t(y0 - dw.min.y) * t.row_stride
                + size_t(x0 - dw.min.x) * t.pixel_stride);
        }
    }
    return true;
}

}  // namespace

bool ExrInput::read(int part, const OIIO::ROI& window, const std::vector<ChannelTarget>& targets,
                    std::string& error, int nthreads) const
{
    exr_const_context_t file = m_context->file;
    const std::string& filename = m_context->filename;
    FlatChunks chunks;
    if (!flat_chunks(file, filename, part, window, targets, chunks, error))
        return false;
    std::atomic<bool> failed { false };
    std::mutex first_error;
    // A few chunks a task: tasks of many chunks leave a thread idle.
    OIIO::parallel_for_chunked(0, chunks.count, 4, [&](int64_t c0, int64_t c1) {
        // Zeroed, as EXR_DECODE_PIPELINE_INITIALIZER makes it ({ 0 }, which
        // clang warns of).
        exr_decode_pipeline_t decoder {};
        ZipChunks zip;
        auto fail = [&](const std::string& why) {
            std::lock_guard<std::mutex> lock(first_error);
            if (!failed.exchange(true))
                error = why;
        };
        core_message.clear();
        for (int64_t c = c0; c < c1 && !failed; ++c) {
            exr_chunk_info_t chunk;
            int64_t x0, y0;
            chunks.origin(c, x0, y0);
            exr_result_t rv = chunks.info(file, part, c, chunk);
            if (rv == EXR_ERR_SUCCESS)
                rv = decoder.channels ? exr_decoding_update(file, part, &chunk, &decoder)
                                      : exr_decoding_initialize(file, part, &chunk, &decoder);
            if (rv != EXR_ERR_SUCCESS) {
                fail(damaged(filename, core_message));
                break;
            }
            std::string why;
            if (!aim_channels(decoder, targets, chunks.dw, x0, y0, filename, why)) {
                fail(why);
                break;
            }
            if (exr_decoding_choose_default_routines(file, part, &decoder) != EXR_ERR_SUCCESS) {
                fail(damaged(filename, core_message));
                break;
            }
            inflate_zip_chunks(decoder, chunks.compression, zip);
            if (exr_decoding_run(file, part, &decoder) != EXR_ERR_SUCCESS) {
                fail(damaged(filename, core_message));
                break;
            }
        }
        exr_decoding_destroy(file, &decoder);
    }, OIIO::paropt(nthreads));
    return !failed;
}

namespace {

/// A deep part, scanlines or tiles, read through one frame buffer.
struct DeepPart {
    std::unique_ptr<Imf::DeepScanLineInputPart> lines;
    std::unique_ptr<Imf::DeepTiledInputPart> tiles;
    Imath::Box2i dw;

    DeepPart(Imf::MultiPartInputFile& file, int part)
        : dw(file.header(part).dataWindow())
    {
        if (file.header(part).type() == Imf::DEEPTILE)
            tiles = std::make_unique<Imf::DeepTiledInputPart>(file, part);
        else
            lines = std::make_unique<Imf::DeepScanLineInputPart>(file, part);
    }

    /// Sets the frame buffer (once: setting it again forgets the sample
    /// counts) and reads the sample counts into it.
    void read_counts(const Imf::DeepFrameBuffer& frame)
    {
        if (tiles) {
            tiles->setFrameBuffer(frame);
            tiles->readPixelSampleCounts(0, tiles->numXTiles(0) - 1, 0, tiles->numYTiles(0) - 1);
        } else {
            lines->setFrameBuffer(frame);
            lines->readPixelSampleCounts(dw.min.y, dw.max.y);
        }
    }

    void read_samples()
    {
        if (tiles)
            tiles->readTiles(0, tiles->numXTiles(0) - 1, 0, tiles->numYTiles(0) - 1);
        else
            lines->readPixels(dw.min.y, dw.max.y);
    }
};

/// Whether a deep data window of width x height, and its per-pixel
/// tables, may be read; else false with `error`.
bool deep_window_allowed(const std::string& filename, int64_t width, int64_t height,
                         const MemoryLimit& limit, std::string& error)
{
    if (width <= 0 || height <= 0) {
        error = damaged(filename, format("deep data window of {}x{}", width, height));
        return false;
    }
    if (!limit.allows(deep_table_bytes(width, height))) {
        error = format("{}: {}", filename,
                       limit.exceeded(format("a deep data window of {}x{}", width, height),
                                      deep_table_bytes(width, height)));
        return false;
    }
    return true;
}

/// Whether `total` samples, up to `most` in one pixel, may be read; else
/// false with `error`. Each sample is held twice for a moment: as OpenEXR
/// decodes it, one array per channel, and as the image keeps it.
bool deep_samples_allowed(const std::string& filename, int64_t width, int64_t height,
                          int nchannels, size_t total, unsigned most, const MemoryLimit& limit,
                          std::string& error)
{
    const double sample_bytes = deep_table_bytes(width, height)
                                + double(total) * (nchannels * sizeof(float) + sizeof(DeepSample));
    if (limit.allows(sample_bytes))
        return true;
    error = format("{}: {}", filename,
                   limit.exceeded(format("{} deep samples (up to {} in one pixel)", total, most),
                                  sample_bytes));
    return false;
}

/// The image of the samples decoded per channel (R, G, B, A, Z and, when
/// there are six, ZBack), `counts` of them per pixel of `dw`.
void gather_samples(const std::vector<std::vector<float>>& values, bool has_back,
                    const std::vector<unsigned>& counts, const Imath::Box2i& dw,
                    DeepImage& image)
{
    const size_t npixels = counts.size(), total = values[0].size();
    image.roi = OIIO::ROI(dw.min.x, dw.max.x + 1, dw.min.y, dw.max.y + 1);
    image.offsets.assign(npixels + 1, 0);
    for (size_t p = 0; p < npixels; ++p)
        image.offsets[p + 1] = image.offsets[p] + counts[p];
    image.samples.resize(total);
    for (size_t s = 0; s < total; ++s) {
        DeepSample& d = image.samples[s];
        d.r = values[0][s];
        d.g = values[1][s];
        d.b = values[2][s];
        d.a = values[3][s];
        d.z = values[4][s];
        d.zback = has_back ? values[5][s] : d.z;
    }
    const size_t first_data = has_back ? 6 : 5, ndata = values.size() - first_data;
    image.data.resize(total * ndata);
    for (size_t c = 0; c < ndata; ++c)
        for (size_t s = 0; s < total; ++s)
            image.data[s * ndata + c] = values[first_data + c][s];
}

}  // namespace

bool read_deep_part(const std::string& filename, int part, const DeepChannels& channels,
                    const MemoryLimit& limit, DeepImage& image, std::string& error)
{
    try {
        Imf::MultiPartInputFile file(filename.c_str());
        const Imath::Box2i dw = file.header(part).dataWindow();
        const int64_t width = int64_t(dw.max.x) - dw.min.x + 1;
        const int64_t height = int64_t(dw.max.y) - dw.min.y + 1;
        if (!deep_window_allowed(filename, width, height, limit, error))
            return false;
        const size_t npixels = size_t(width) * size_t(height);
        DeepPart deep(file, part);

        // One frame buffer: pixel (x, y) at base + x * xstride + y * ystride.
        // Each channel's samples go in one array, through a pointer per
        // pixel to its first sample there, filled in once the counts are
        // known.
        const bool has_back = !channels.depth_back.empty();
        std::vector<const std::string*> names = { &channels.color[0], &channels.color[1],
                                                  &channels.color[2], &channels.color[3],
                                                  &channels.depth };
        if (has_back)
            names.push_back(&channels.depth_back);
        for (const std::string& name : channels.data)
            names.push_back(&name);
        const int nchannels = int(names.size());
        const size_t origin = size_t(dw.min.y) * size_t(width) + size_t(dw.min.x);
        std::vector<unsigned> counts(npixels, 0);
        std::vector<std::vector<float*>> firsts(nchannels, std::vector<float*>(npixels, nullptr));
        Imf::DeepFrameBuffer frame;
        frame.insertSampleCountSlice(Imf::Slice(Imf::UINT, frame_base(counts.data(), origin),
                                                sizeof(unsigned), sizeof(unsigned) * size_t(width)));
        for (int c = 0; c < nchannels; ++c)
            frame.insert(*names[c],
                         Imf::DeepSlice(Imf::FLOAT, frame_base(firsts[c].data(), origin),
                                        sizeof(float*), sizeof(float*) * size_t(width),
                                        sizeof(float)));
        deep.read_counts(frame);
        size_t total = 0;
        unsigned most = 0;
        for (unsigned n : counts) {
            total += n;
            most = std::max(most, n);
        }
        if (!deep_samples_allowed(filename, width, height, nchannels, total, most, limit, error))
            return false;
        std::vector<std::vector<float>> values(nchannels, std::vector<float>(total));
        for (int c = 0; c < nchannels; ++c) {
            size_t at = 0;
            for (size_t p = 0; p < npixels; ++p) {
                firsts[c][p] = values[c].data() + at;
                at += counts[p];
            }
        }
        deep.read_samples();
        gather_samples(values, has_back, counts, dw, image);
        image.data_names = channels.data;
        return true;
    } catch (const std::exception& e) {
        error = damaged(filename, OIIO::Strutil::replace(e.what(), "\n", " ", true));
    } catch (...) {
        error = damaged(filename, "");
    }
    return false;
}

}  // namespace defocus
