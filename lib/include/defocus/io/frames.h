// Frame sequences in oiiotool's syntax: file patterns with '#' (four
// digits), '@' (one digit each), "%0Nd" or an embedded range
// ("shot.1-10#.exr"), and frame lists such as "1001-1100", "1-99x2",
// "1,5,9-12".
#pragma once

#include <string>
#include <vector>

#include <defocus/shot/shot.h>

namespace defocus {

/// True when `path` is a frame pattern rather than one file.
bool is_frame_pattern(const std::string& path);

/// The file of `frame` in a frame pattern; `path` itself when it is not a
/// pattern.
std::string frame_path(const std::string& path, int frame);

/// The files a shot reads for `frame`: its inputs with their patterns
/// filled in, at the frame's source_frame().
std::vector<std::string> frame_inputs(const Shot& shot, int frame);

/// The read options of `frame`: a --depth file pattern filled in, at the
/// frame's source_frame().
ReadOptions frame_read_options(const Shot& shot, int frame);

/// The frame patterns a shot reads: its inputs, depth file and holdout
/// that are patterns.
std::vector<std::string> sequence_files(const Shot& shot);

/// The frame whose input files `frame` reads: itself, unless they are
/// missing and the shot holds missing frames (MissingFrames::Hold): then
/// the nearest earlier frame on disk whose files are all there, else the
/// nearest later one.
int source_frame(const Shot& shot, int frame);

/// Every file a shot reads to render `frames`: their inputs and depth
/// files (frame patterns filled in at each frame's source_frame()), the
/// aperture mask, the PSF image and the colour config.
std::vector<std::string> files_read(const Shot& shot, const std::vector<int>& frames);

/// True when a shot is a sequence: it has a frame list or a frame pattern
/// among its inputs.
bool is_sequence(const Shot& shot);

/// The frames a shot renders, in order: its frame list; else the range
/// embedded in an input pattern; else the span of the frames of the first
/// input pattern found on disk (a gap in it is a missing frame); else one
/// frame (a still). Frames whose input files are missing are an error
/// naming them, unless the shot skips them (left out, and listed in
/// `missing` when given) or holds them (kept: they read an earlier frame's
/// files, see source_frame). False with `error` when the list is
/// malformed, a pattern finds no files, frames are missing, or a still has
/// keyframes (they need frames).
bool shot_frames(const Shot& shot, std::vector<int>& frames, std::string& error,
                 std::vector<int>* missing = nullptr);

/// A host's frame pattern names a frame of a file as a file of its own
/// (oiiotool --frames 1001-1005 shot.#.dof asks for shot.1001.dof): where
/// `name` does not exist but is such a name of one that does, that file
/// and the frame; else false.
bool numbered_file(const std::string& name, std::string& file, int& frame);

/// Frames as ranges for messages: "1001-1003, 1007, 1010-1012" (sorted;
/// the first dozen ranges).
std::string frame_ranges(const std::vector<int>& frames);

/// Parses "K/N" (1 <= K <= N), the K-th of N chunks, into `k` and `n`; else
/// false with `error` naming `option`.
bool parse_chunk(const std::string& option, const std::string& text, int& k, int& n,
                 std::string& error);

/// The K-th (1-based) of `n` chunks of `frames`: contiguous runs of frames
/// in order, their sizes differing by at most one, so that every frame is
/// in exactly one chunk (a chunk is empty when there are fewer frames than
/// chunks). A chunk reads neighbouring frames, as a render farm task wants.
std::vector<int> chunk_frames(const std::vector<int>& frames, int k, int n);

/// The file each of `frames` writes through the output `pattern` ("" gives
/// none), named after `option` ("-o", "--preview") in errors: more than
/// one frame needs a frame pattern.
bool frame_outputs(const std::string& option, const std::string& pattern,
                   const std::vector<int>& frames, std::vector<std::string>& files,
                   std::string& error);

}  // namespace defocus
