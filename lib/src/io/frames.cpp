#include <defocus/io/frames.h>

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string_view>
#include <regex>

#include <sys/stat.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

#include <defocus/shot/option_value.h>
#include <defocus/shot/setting_words.h>

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

/// `frames` in order. Most lists come in order, and are only checked.
std::vector<int> sorted(std::vector<int> frames)
{
    if (!std::is_sorted(frames.begin(), frames.end()))
        std::sort(frames.begin(), frames.end());
    return frames;
}

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
    const std::vector<int> in_order = sorted(frames);
    const auto twice = std::adjacent_find(in_order.begin(), in_order.end());
    if (twice != in_order.end()) {
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
    /// The frame number as printf's "%0Nd" writes it (a minus sign counts
    /// in the width). By hand, not by format(): a shot looks up every
    /// frame's files.
    std::string number(int frame) const
    {
        char digits[16];
        const char* end = std::to_chars(digits, digits + sizeof(digits), std::abs(int64_t(frame))).ptr;
        const size_t length = size_t(end - digits) + (frame < 0 ? 1 : 0);
        std::string text = frame < 0 ? "-" : "";
        text.append(size_t(width) > length ? size_t(width) - length : 0, '0');
        return text.append(digits, size_t(end - digits));
    }
    std::string path(int frame) const { return prefix + number(frame) + suffix; }
};

/// The frame an entry of the pattern's folder is, when it is one: the
/// name path() writes for some frame, negative ones too.
std::optional<int> frame_of_entry(const FrameNumbering& pattern, const std::string& name_prefix,
                                  const std::string& entry)
{
    const std::string& suffix = pattern.suffix;
    if (entry.size() <= name_prefix.size() + suffix.size()
        || entry.compare(0, name_prefix.size(), name_prefix) != 0
        || entry.compare(entry.size() - suffix.size(), suffix.size(), suffix) != 0)
        return std::nullopt;
    const std::string_view digits(entry.data() + name_prefix.size(),
                                  entry.size() - name_prefix.size() - suffix.size());
    int frame = 0;
    const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), frame);
    if (error != std::errc() || end != digits.data() + digits.size()
        || digits != pattern.number(frame))
        return std::nullopt;
    return frame;
}

/// Whether a folder has an entry of this name. What the entry is does not
/// matter here: a symbolic link loop or a folder where a frame should be is
/// that frame's error when it is read, not a missing frame.
bool has_entry(const std::string& path)
{
    struct stat entry;
    return ::lstat(path.c_str(), &entry) == 0;
}

/// The frames of a pattern that name entries of its folder, in order; none
/// when the folder cannot be listed. What an entry is does not matter here:
/// a symbolic link loop or a folder among the frames is that frame's error
/// when it is read. (OpenImageIO's scan stops at the first entry it cannot
/// examine, dropping the frames after it.) When the frame number is in a
/// folder's name (`shot.#/beauty.exr`), the folders are listed, and only
/// the frames whose folder is there are looked up: a million frames were a
/// million lookups.
std::optional<std::vector<int>> scan_frames(const FrameNumbering& pattern)
{
    if (const size_t below = pattern.suffix.find('/'); below != std::string::npos) {
        FrameNumbering folders = pattern;
        folders.suffix.resize(below);
        std::optional<std::vector<int>> frames = scan_frames(folders);
        if (frames)
            frames->erase(std::remove_if(frames->begin(), frames->end(),
                                         [&](int frame) { return !has_entry(pattern.path(frame)); }),
                          frames->end());
        return frames;
    }
    const size_t slash = pattern.prefix.rfind('/');
    const std::string folder =
        slash == std::string::npos ? "." : pattern.prefix.substr(0, std::max<size_t>(slash, 1));
    const std::string name_prefix =
        slash == std::string::npos ? pattern.prefix : pattern.prefix.substr(slash + 1);
    std::vector<int> frames;
    std::error_code ec;
    std::filesystem::directory_iterator it(folder, ec), end;
    for (; !ec && it != end; it.increment(ec))
        if (auto frame = frame_of_entry(pattern, name_prefix, it->path().filename().string()))
            frames.push_back(*frame);
    if (ec)
        return std::nullopt;
    std::sort(frames.begin(), frames.end());
    frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
    return frames;
}

/// The numbering of a frame pattern; false for a name that is not one.
bool parse_numbering(const std::string& path, FrameNumbering& numbering)
{
    std::string normalized, range;
    return parse_frame_pattern(path, normalized, range) && numbering.parse(normalized);
}

/// The frames of a pattern found on disk, in order ({} for a name that
/// is not a pattern).
std::vector<int> frames_on_disk(const std::string& pattern)
{
    FrameNumbering numbering;
    if (!parse_numbering(pattern, numbering))
        return {};
    return scan_frames(numbering).value_or(std::vector<int>());
}

/// What to say when no file matches `pattern`: its files may be numbered
/// without the padding it asks for ('#' is four digits).
std::string unpadded_hint(const std::string& pattern)
{
    FrameNumbering numbering;
    if (parse_numbering(pattern, numbering) && numbering.width > 1) {
        numbering.width = 1;
        const std::vector<int> found = scan_frames(numbering).value_or(std::vector<int>());
        if (!found.empty()) {
            const std::string folder = Filesystem::parent_path(numbering.prefix);
            auto name = [&](int frame) {
                return numbering.path(frame).substr(folder.empty() ? 0 : folder.size() + 1);
            };
            return format(", but {}@{} matches {} ({} to {})", numbering.prefix,
                          numbering.suffix, found.size(), name(found.front()),
                          name(found.back()));
        }
    }
    return format(" (give {} to name them)", mention("frames"));
}

/// A shot's frame patterns, and which of their files are on disk. A check
/// of the whole shot asks about every frame (up to a million) of each
/// pattern: one listing of the pattern's folder costs less than a lookup of
/// each file, and parsing the pattern far more. A check of one frame looks
/// its files up, and lists a folder only to find the frame a missing one
/// holds.
class SequenceFiles {
public:
    enum class Check { OneFrame, WholeShot };

    SequenceFiles(const Shot& shot, Check check)
        : hold_(shot.missing_frames == MissingFrames::Hold)
    {
        for (const std::string& file : sequence_files(shot))
            if (FrameNumbering numbering; parse_numbering(file, numbering))
                patterns_.push_back({ numbering, check == Check::WholeShot
                                                     ? scan_frames(numbering)
                                                     : std::nullopt });
    }
    bool empty() const { return patterns_.empty(); }
    /// The first file of `frame` that is missing, "" when all are there.
    std::string first_missing(int frame) const
    {
        for (const Pattern& pattern : patterns_)
            if (!pattern.has(frame))
                return pattern.numbering.path(frame);
        return "";
    }
    bool exist(int frame) const
    {
        return std::all_of(patterns_.begin(), patterns_.end(),
                           [frame](const Pattern& pattern) { return pattern.has(frame); });
    }
    /// See source_frame().
    int source(int frame) const
    {
        if (!hold_ || empty() || exist(frame))
            return frame;
        // The frames on disk of the first pattern, nearest earlier first,
        // then nearest later.
        const std::vector<int>& on_disk = patterns_.front().on_disk();
        const auto after = std::upper_bound(on_disk.begin(), on_disk.end(), frame);
        for (auto earlier = std::make_reverse_iterator(after); earlier != on_disk.rend(); ++earlier)
            if (*earlier != frame && exist(*earlier))
                return *earlier;
        for (auto later = after; later != on_disk.end(); ++later)
            if (exist(*later))
                return *later;
        return frame;
    }

private:
    struct Pattern {
        FrameNumbering numbering;
        std::optional<std::vector<int>> listing;  ///< its folder's frames, when listed

        const std::vector<int>& on_disk()
        {
            if (!listing)
                listing = scan_frames(numbering);
            static const std::vector<int> none;
            return listing ? *listing : none;
        }
        /// A listing answers for every frame (a million negative frames
        /// were a million lookups); a file lookup when the folder is not
        /// listed or cannot be.
        bool has(int frame) const
        {
            if (listing)
                return std::binary_search(listing->begin(), listing->end(), frame);
            return has_entry(numbering.path(frame));
        }
    };
    bool hold_;
    mutable std::vector<Pattern> patterns_;  ///< listed when first needed
};

}  // namespace

bool is_frame_pattern(const std::string& path)
{
    std::string normalized, range;
    return parse_frame_pattern(path, normalized, range);
}

std::string frame_path(const std::string& path, int frame)
{
    FrameNumbering numbering;
    return parse_numbering(path, numbering) ? numbering.path(frame) : path;
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

int source_frame(const Shot& shot, int frame)
{
    return SequenceFiles(shot, SequenceFiles::Check::OneFrame).source(frame);
}

std::vector<std::string> sequence_files(const Shot& shot)
{
    std::vector<std::string> patterns;
    for (const std::string& file : shot.inputs)
        if (is_frame_pattern(file))
            patterns.push_back(file);
    for (const std::string* file : { &shot.read.depth, &shot.holdout })
        if (is_frame_pattern(*file))
            patterns.push_back(*file);
    return patterns;
}

std::vector<std::string> files_read(const Shot& shot, const std::vector<int>& frames)
{
    const SequenceFiles sequence(shot, SequenceFiles::Check::WholeShot);
    std::vector<int> sources;
    for (int frame : frames)
        sources.push_back(sequence.source(frame));
    std::vector<std::string> files;
    for (const std::string& file : shot_files(shot)) {
        FrameNumbering numbering;
        if (!parse_numbering(file, numbering)) {
            files.push_back(file);
            continue;
        }
        for (int source : sources)
            files.push_back(numbering.path(source));
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
    const std::vector<int> in_order = sorted(frames);
    std::vector<std::string> ranges;
    for (size_t i = 0; i < in_order.size();) {
        size_t j = i;
        while (j + 1 < in_order.size() && int64_t(in_order[j + 1]) == int64_t(in_order[j]) + 1)
            ++j;
        ranges.push_back(j == i ? std::to_string(in_order[i])
                                : format("{}-{}", in_order[i], in_order[j]));
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
    const auto first_input_pattern =
        std::find_if(shot.inputs.begin(), shot.inputs.end(), is_frame_pattern);
    if (!shot.frames.empty()) {
        if (!enumerate_frames(shot.frames, frames, error, setting_label(shot, "frames")))
            return false;
    } else if (first_input_pattern == shot.inputs.end()) {
        if (is_animated(shot)) {
            error = "the camera has keyframes but the input is one image: give "
                    + mention("frames");
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
                error = format("{}: no files match{}", first, unpadded_hint(first));
                return false;
            }
            range = found.front() == found.back() ? std::to_string(found.front())
                                                  : format("{}-{}", found.front(), found.back());
        }
        if (!enumerate_frames(range, frames, error, first))
            return false;
    }
    const SequenceFiles sequence(shot, SequenceFiles::Check::WholeShot);
    if (sequence.empty())
        return true;

    std::vector<int> missing, present;
    for (int frame : frames)
        (sequence.exist(frame) ? present : missing).push_back(frame);
    if (missing.empty())
        return true;
    if (missing_frames)
        *missing_frames = missing;
    const std::string which = format("{}: no such file; frames with input files missing: {}",
                                     sequence.first_missing(missing.front()),
                                     frame_ranges(missing));
    if (shot.missing_frames == MissingFrames::Error) {
        error = format("{} ({} or {} renders the shot without them)", which,
                       mention("missing-frames", "skip"), mention("missing-frames", "hold"));
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

bool numbered_file(const std::string& name, std::string& file, int& frame)
{
    const std::string extension = Filesystem::extension(name);
    if (extension.empty() || Filesystem::exists(name))
        return false;
    const std::string stem = name.substr(0, name.size() - extension.size());
    const size_t dot = stem.rfind('.');
    if (dot == std::string::npos)
        return false;
    const std::string number = stem.substr(dot + 1);
    const size_t digits_from = number.size() > 1 && number[0] == '-' ? 1 : 0;
    if (number.size() <= digits_from || number.size() > 9
        || !std::all_of(number.begin() + digits_from, number.end(),
                        [](char c) { return c >= '0' && c <= '9'; }))
        return false;
    const std::string candidate = stem.substr(0, dot) + extension;
    if (!Filesystem::exists(candidate))
        return false;
    file = candidate;
    frame = Strutil::stoi(number);
    return true;
}

}  // namespace defocus
