#include <defocus/io/frames.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

namespace defocus {

using OIIO::Strutil::fmt::format;
namespace Filesystem = OIIO::Filesystem;

namespace {

/// oiiotool's parse: the printf pattern and any embedded frame range.
bool parse_frame_pattern(const std::string& path, std::string& normalized,
                         std::string& range)
{
    return Filesystem::parse_pattern(path.c_str(), 0, normalized, range);
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
    std::vector<std::string> names;
    if (!Filesystem::enumerate_file_sequence(normalized, { frame }, names) || names.empty())
        return path;
    return names.front();
}

std::vector<std::string> frame_inputs(const Shot& shot, int frame)
{
    std::vector<std::string> files;
    for (const std::string& input : shot.inputs)
        files.push_back(frame_path(input, frame));
    return files;
}

ReadOptions frame_read_options(const Shot& shot, int frame)
{
    ReadOptions options = shot.read;
    options.depth       = frame_path(options.depth, frame);
    return options;
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

bool shot_frames(const Shot& shot, std::vector<int>& frames, std::string& error)
{
    frames.clear();
    if (!shot.frames.empty()) {
        if (!Filesystem::enumerate_sequence(shot.frames, frames) || frames.empty()) {
            error = format("--frames: '{}' is not a frame list (e.g. 1001-1100, 1-99x2, "
                           "1,5,9-12)",
                           shot.frames);
            return false;
        }
        return true;
    }
    for (const std::string& input : shot.inputs) {
        std::string normalized, range;
        if (!parse_frame_pattern(input, normalized, range))
            continue;
        if (!range.empty()) {
            if (!Filesystem::enumerate_sequence(range, frames) || frames.empty()) {
                error = format("{}: '{}' is not a frame range", input, range);
                return false;
            }
            return true;
        }
        std::vector<std::string> names;
        if (!Filesystem::scan_for_matching_filenames(normalized, frames, names)
            || frames.empty()) {
            error = format("{}: no files match (give --frames to name them)", input);
            return false;
        }
        return true;
    }
    if (is_animated(shot)) {
        error = "the camera has keyframes but the input is one image: give --frames";
        return false;
    }
    frames = { 1 };
    return true;
}

}  // namespace defocus
