// Internal: OpenEXR's ZIP and ZIPS chunks inflated by libdeflate.
//
// OpenEXR 3.1 inflates with zlib, a third of the time of reading a
// zip-compressed frame; libdeflate decodes the same zlib streams two to
// three times faster, and checks them as strictly (the stream's length and
// Adler-32 sum). What follows inflation is OpenEXR's: undo the byte
// predictor, then interleave the two halves of the chunk.
#pragma once

#include <OpenEXR/openexr.h>

namespace defocus {

/// What inflate_zip_chunk() needs beside the pipeline: the decompression
/// it stands in for, for the chunks it leaves to OpenEXR.
struct ZipChunks {
    exr_result_t (*fallback)(exr_decode_pipeline_t*) = nullptr;
};

/// Makes `decoder`, set up by exr_decoding_choose_default_routines() for a
/// part with `compression`, inflate ZIP and ZIPS chunks with libdeflate.
/// `zip` must outlive the decoder's runs.
void inflate_zip_chunks(exr_decode_pipeline_t& decoder, exr_compression_t compression,
                        ZipChunks& zip);

}  // namespace defocus
