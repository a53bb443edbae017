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
/// filled in.
std::vector<std::string> frame_inputs(const Shot& shot, int frame);

/// The read options of `frame`: a --depth file pattern filled in.
ReadOptions frame_read_options(const Shot& shot, int frame);

/// True when a shot is a sequence: it has a frame list or a frame pattern
/// among its inputs.
bool is_sequence(const Shot& shot);

/// The frames a shot renders, in order: its frame list; else the range
/// embedded in an input pattern; else the frames of the first input
/// pattern found on disk; else one frame (a still). False with `error` when the list is malformed,
/// a pattern finds no files, or a still has keyframes (they need frames).
bool shot_frames(const Shot& shot, std::vector<int>& frames, std::string& error);

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
