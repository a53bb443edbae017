#include <defocus/io/frames.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <regex>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

#include <defocus/shot/option_value.h>

namespace defocus {

using OIIO::Strutil::fmt::format;
namespace Filesystem = OIIO::Filesystem;
namespace Strutil = OIIO::Strutil;

namespace {

/// A shot renders at most this many frames: a day of 24 fps is 2 million,
/// no sequence is longer than a few hundred thousand, and a typo such as
/// 1-2000000000 would otherwise take gigabytes before the first frame.
/// (OpenImageIO's enumerate_sequence, not used here, reads
/// "1001-11001040:2" as eleven million frames and walks every frame of a
/// range, however large its step.)
constexpr int64_t max_frames = 1000000;

/// One part of a frame list: "A", "A-B", "A-BxN" (every Nth frame) or
/// "A-ByN" (all but every Nth), in oiiotool's meaning: from A towards B
/// (downwards when B < A; a negative N walks from B towards A instead).
struct FrameRange {
    int64_t first = 0, last = 0, step = 1;
    bool all_but = false;

    bool parse(const std::string& part)
    {
        OIIO::string_view rest(part);
        int a = 0, b = 0, n = 1;
        if (!OIIO::Strutil::parse_int(rest, a))
            return false;
        b = a;
        if (OIIO::Strutil::parse_char(rest, '-') && !OIIO::Strutil::parse_int(rest, b))
            return false;
        all_but = rest.size() && rest[0] == 'y';
        if ((OIIO::Strutil::parse_char(rest, 'x') || OIIO::Strutil::parse_char(rest, 'y'))
            && !OIIO::Strutil::parse_int(rest, n))
            return false;
        if (!rest.empty() || n == 0)
            return false;
        first = n > 0 ? a : b;
        last  = n > 0 ? b : a;
        step  = std::abs(int64_t(n));
        return true;
    }
    int64_t span() const { return std::abs(last - first) + 1; }
    /// The frames it names, counted, not walked.
    int64_t count() const
    {
        const int64_t stepped = (span() - 1) / step + 1;
        return all_but ? span() - stepped : stepped;
    }
    /// Appends its frames in order, in time proportional to their number
    /// (a step of two billion names two frames).
    void append_to(std::vector<int>& frames) const
    {
        const int64_t direction = last >= first ? 1 : -1;
        const int64_t end = last + direction;
        for (int64_t base = first; base != end && (base - end) * direction < 0;
             base += direction * step) {
            if (!all_but) {
                frames.push_back(int(base));
                continue;
            }
            for (int64_t f = base + direction; f != base + direction * step && f != end; f += direction)
                frames.push_back(int(f));
        }
    }
};

/// Reads a frame list ("1-10x2,15,20-30") into `frames`, in its order.
/// At most max_frames frames, counted before any is listed, and none
/// twice (a frame listed twice would be rendered and written twice).
bool enumerate_frames(const std::string& list, std::vector<int>& frames, std::string& error,
                      const std::string& what)
{
    std::vector<FrameRange> ranges;
    int64_t count = 0;
    for (const std::string& part : OIIO::Strutil::splits(list, ",")) {
        FrameRange range;
        if (!range.parse(part)) {
            error = format("{}: '{}' is not a frame list (e.g. 1001-1100, 1-99x2, 1,5,9-12)",
                           what, list);
            return false;
        }
        ranges.push_back(range);
        count += range.count();
    }
    if (count > max_frames) {
        error = format("{}: '{}' names {} frames; a shot renders at most {}", what, list, count,
                       max_frames);
        return false;
    }
    frames.clear();
    frames.reserve(size_t(count));
    for (const FrameRange& range : ranges)
        range.append_to(frames);
    if (frames.empty()) {
        error = format("{}: '{}' names no frames", what, list);
        return false;
    }
    std::vector<int> sorted = frames;
    std::sort(sorted.begin(), sorted.end());
    const auto twice = std::adjacent_find(sorted.begin(), sorted.end());
    if (twice != sorted.end()) {
        error = format("{}: '{}' names frame {} more than once", what, list, *twice);
        return false;
    }
    return true;
}

/// oiiotool's parse: the printf pattern and any embedded frame range.
bool parse_frame_pattern(const std::string& path, std::string& normalized,
                         std::string& range)
{
    return Filesystem::parse_pattern(path.c_str(), 0, normalized, range);
}

/// A printf pattern as parse_pattern gives it ("shot.%04d.exr"), split at
/// its frame number. Any other '%' is a character of the name: OpenImageIO
/// formats the whole pattern, and aborts on "a%s.#.exr".
struct FrameNumbering {
    std::string prefix, suffix;
    int width = 0;  ///< digits, zero-padded

    /// The last "%d" or "%0Nd" is the frame number: it sits before the
    /// extension, where '#' and '@' put theirs.
    bool parse(const std::string& normalized)
    {
        static const std::regex number("%0?([0-9]{0,2})d");
        std::sregex_iterator last;
        for (std::sregex_iterator it(normalized.begin(), normalized.end(), number), end;
             it != end; ++it)
            last = it;
        if (last == std::sregex_iterator())
            return false;
        const std::smatch& found = *last;
        prefix = normalized.substr(0, size_t(found.position(0)));
        suffix = found.suffix();
        width  = found[1].length() ? std::stoi(found[1]) : 0;
        return true;
    }
    std::string path(int frame) const
    {
        return format("{}{:0{}d}{}", prefix, frame, width, suffix);
    }
};

/// The frames of a pattern that name entries of its folder, in order.
/// What an entry is does not matter here: a symbolic link loop or a folder
/// among the frames is that frame's error when it is read. (OpenImageIO's
/// scan stops at the first entry it cannot examine, dropping the frames
/// after it.)
std::vector<int> scan_frames(const FrameNumbering& pattern)
{
    const size_t slash = pattern.prefix.rfind('/');
    const std::string folder =
        slash == std::string::npos ? "." : pattern.prefix.substr(0, std::max<size_t>(slash, 1));
    const std::string name_prefix =
        slash == std::string::npos ? pattern.prefix : pattern.prefix.substr(slash + 1);
    if (pattern.suffix.find('/') != std::string::npos)
        return {};  // the frame number in a folder's name
    auto literal = [](const std::string& text) {
        return std::regex_replace(text, std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)");
    };
    // The digits the pattern writes: padded to the width, with no leading
    // zero past it.
    const std::string width = std::to_string(pattern.width);
    const std::string digits = pattern.width == 0
                                   ? "(0|[1-9][0-9]*)"
                                   : "([0-9]{" + width + "}|[1-9][0-9]{" + width + ",})";
    const std::regex frame_name(literal(name_prefix) + digits + literal(pattern.suffix));
    std::vector<int> frames;
    std::error_code ec;
    for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end;
         it.increment(ec)) {
        const std::string entry = it->path().filename().string();
        std::smatch frame;
        if (std::regex_match(entry, frame, frame_name) && frame[1].length() <= 9)
            frames.push_back(std::stoi(frame[1]));
    }
    std::sort(frames.begin(), frames.end());
    frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
    return frames;
}

/// Whether a folder has an entry of this name. What the entry is does not
/// matter here: a symbolic link loop or a folder where a frame should be is
/// that frame's error when it is read, not a missing frame.
bool has_entry(const std::string& path)
{
    std::error_code ec;
    return std::filesystem::exists(std::filesystem::symlink_status(path, ec));
}

/// The frames of a pattern found on disk, in order ({} for a name that
/// is not a pattern).
std::vector<int> frames_on_disk(const std::string& pattern)
{
    std::string normalized, range;
    FrameNumbering numbering;
    if (!parse_frame_pattern(pattern, normalized, range) || !numbering.parse(normalized))
        return {};
    return scan_frames(numbering);
}

}  // namespace

bool is_frame_pattern(const std::string& path)
{
    std::string normalized, range;
    return parse_frame_pattern(path, normalized, range);
}

std::string frame_path(const std::string& path, int frame)
{
    std::string normalized, range;
    if (!parse_frame_pattern(path, normalized, range))
        return path;
    FrameNumbering numbering;
    return numbering.parse(normalized) ? numbering.path(frame) : path;
}

std::vector<std::string> frame_inputs(const Shot& shot, int frame)
{
    const int source = source_frame(shot, frame);
    std::vector<std::string> files;
    for (const std::string& input : shot.inputs)
        files.push_back(frame_path(input, source));
    return files;
}

ReadOptions frame_read_options(const Shot& shot, int frame)
{
    ReadOptions options = shot.read;
    options.depth       = frame_path(options.depth, source_frame(shot, frame));
    return options;
}

bool frame_inputs_exist(const Shot& shot, int frame)
{
    for (const std::string& file : sequence_files(shot))
        if (!has_entry(frame_path(file, frame)))
            return false;
    return true;
}

int source_frame(const Shot& shot, int frame)
{
    if (shot.missing_frames != MissingFrames::Hold || frame_inputs_exist(shot, frame))
        return frame;
    // The frames on disk of the first pattern, nearest earlier first, then
    // nearest later.
    const std::vector<std::string> patterns = sequence_files(shot);
    if (patterns.empty())
        return frame;
    std::vector<int> candidates = frames_on_disk(patterns.front());
    const auto after = std::upper_bound(candidates.begin(), candidates.end(), frame);
    std::reverse(candidates.begin(), after);
    for (int candidate : candidates)
        if (candidate != frame && frame_inputs_exist(shot, candidate))
            return candidate;
    return frame;
}

std::vector<std::string> sequence_files(const Shot& shot)
{
    std::vector<std::string> patterns;
    for (const std::string& file : shot.inputs)
        if (is_frame_pattern(file))
            patterns.push_back(file);
    if (is_frame_pattern(shot.read.depth))
        patterns.push_back(shot.read.depth);
    return patterns;
}

std::vector<std::string> files_read(const Shot& shot, const std::vector<int>& frames)
{
    std::vector<std::string> files;
    for (const std::string& file : shot_files(shot)) {
        if (!is_frame_pattern(file)) {
            files.push_back(file);
            continue;
        }
        for (int frame : frames)
            files.push_back(frame_path(file, source_frame(shot, frame)));
    }
    return files;
}

bool is_sequence(const Shot& shot)
{
    if (!shot.frames.empty())
        return true;
    for (const std::string& input : shot.inputs)
        if (is_frame_pattern(input))
            return true;
    return false;
}

std::string frame_ranges(const std::vector<int>& frames)
{
    std::vector<int> sorted = frames;
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::string> ranges;
    for (size_t i = 0; i < sorted.size();) {
        size_t j = i;
        while (j + 1 < sorted.size() && int64_t(sorted[j + 1]) == int64_t(sorted[j]) + 1)
            ++j;
        ranges.push_back(j == i ? std::to_string(sorted[i])
                                : format("{}-{}", sorted[i], sorted[j]));
        i = j + 1;
    }
    constexpr size_t shown = 12;
    if (ranges.size() > shown) {
        const size_t more = ranges.size() - shown;
        ranges.resize(shown);
        ranges.push_back(format("and {} more range(s)", more));
    }
    return Strutil::join(ranges, ", ");
}

bool shot_frames(const Shot& shot, std::vector<int>& frames, std::string& error,
                 std::vector<int>* missing_frames)
{
    frames.clear();
    if (missing_frames)
        missing_frames->clear();
    const std::vector<std::string> patterns = sequence_files(shot);
    const auto first_input_pattern =
        std::find_if(shot.inputs.begin(), shot.inputs.end(), is_frame_pattern);
    if (!shot.frames.empty()) {
        if (!enumerate_frames(shot.frames, frames, error, "--frames"))
            return false;
    } else if (first_input_pattern == shot.inputs.end()) {
        if (is_animated(shot)) {
            error = "the camera has keyframes but the input is one image: give --frames";
            return false;
        }
        frames = { 1 };
    } else {
        // The range embedded in the first input's pattern, else the span of
        // its frames on disk: a gap in it is a missing frame, not one less.
        const std::string& first = *first_input_pattern;
        std::string normalized, range;
        parse_frame_pattern(first, normalized, range);
        if (range.empty()) {
            const std::vector<int> found = frames_on_disk(first);
            if (found.empty()) {
                error = format("{}: no files match (give --frames to name them)", first);
                return false;
            }
            range = found.front() == found.back() ? std::to_string(found.front())
                                                  : format("{}-{}", found.front(), found.back());
        }
        if (!enumerate_frames(range, frames, error, first))
            return false;
    }
    if (patterns.empty())
        return true;

    std::vector<int> missing, present;
    for (int frame : frames)
        (frame_inputs_exist(shot, frame) ? present : missing).push_back(frame);
    if (missing.empty())
        return true;
    if (missing_frames)
        *missing_frames = missing;
    std::string first_missing;
    for (const std::string& file : patterns)
        if (first_missing.empty() && !has_entry(frame_path(file, missing.front())))
            first_missing = frame_path(file, missing.front());
    const std::string which = format("{}: no such file; frames with input files missing: {}",
                                     first_missing, frame_ranges(missing));
    if (shot.missing_frames == MissingFrames::Error) {
        error = which + " (--missing-frames skip or hold renders the shot without them)";
        return false;
    }
    if (present.empty()) {
        error = which + ": the shot has no frame to render";
        return false;
    }
    if (shot.missing_frames == MissingFrames::Skip)
        frames = std::move(present);
    return true;
}

bool parse_chunk(const std::string& option, const std::string& text, int& k, int& n,
                 std::string& error)
{
    const std::vector<std::string> parts = Strutil::splits(text, "/");
    if (parts.size() == 2 && parse_whole_number(option, parts[0], 1, 1e6, k, error)
        && parse_whole_number(option, parts[1], 1, 1e6, n, error) && k <= n)
        return true;
    error = format("{}: '{}' is not a chunk K/N with 1 <= K <= N (e.g. 2/10)", option, text);
    return false;
}

std::vector<int> chunk_frames(const std::vector<int>& frames, int k, int n)
{
    const size_t count = frames.size();
    const size_t begin = count * size_t(k - 1) / size_t(n);
    const size_t end   = count * size_t(k) / size_t(n);
    return std::vector<int>(frames.begin() + begin, frames.begin() + end);
}

bool frame_outputs(const std::string& option, const std::string& pattern,
                   const std::vector<int>& frames, std::vector<std::string>& files,
                   std::string& error)
{
    files.clear();
    if (pattern.empty())
        return true;
    if (frames.size() > 1 && !is_frame_pattern(pattern)) {
        error = format("{} {}: {} frames need a frame pattern in the name, e.g. out.#.exr",
                       option, pattern, frames.size());
        return false;
    }
    for (int frame : frames)
        files.push_back(frame_path(pattern, frame));
    return true;
}

}  // namespace defocus
