#include <defocus/shot/shot_file.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <nlohmann/json.hpp>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>

namespace defocus {

using json = nlohmann::ordered_json;
using OIIO::Strutil::fmt::format;
namespace fs = std::filesystem;

namespace {

std::string resolve(const std::string& path, const std::string& directory)
{
    if (path.empty() || fs::path(path).is_absolute() || directory.empty())
        return path;
    return (fs::path(directory) / path).lexically_normal().string();
}

std::string relative_to(const std::string& path, const std::string& directory)
{
    if (path.empty())
        return path;
    std::error_code ec;
    const fs::path absolute = fs::absolute(path, ec);
    const fs::path base     = fs::absolute(directory.empty() ? "." : directory, ec);
    const fs::path relative = absolute.lexically_normal().lexically_relative(base.lexically_normal());
    if (ec || relative.empty() || *relative.begin() == "..")
        return absolute.lexically_normal().string();
    return relative.string();
}

std::string number_text(const json& value)
{
    return format("{}", value.get<double>());
}

bool is_point(const json& value)
{
    return value.is_array() && value.size() == 2 && value[0].is_number()
           && value[1].is_number();
}

/// The command-line text of a JSON value of the given kind, or false with
/// `error` saying what was expected.
bool to_text(const json& value, ShotValueKind kind, std::string& text, std::string& error)
{
    switch (kind) {
    case ShotValueKind::Number:
        if (!value.is_number())
            break;
        text = number_text(value);
        return true;
    case ShotValueKind::Keyframes:
    case ShotValueKind::Point: {
        const bool point = kind == ShotValueKind::Point;
        auto component   = [&](const json& v) {
            return point ? is_point(v) : v.is_number();
        };
        auto value_text = [&](const json& v) {
            return point ? number_text(v[0]) + "," + number_text(v[1]) : number_text(v);
        };
        if (component(value)) {
            text = value_text(value);
            return true;
        }
        if (!value.is_object() || value.empty())
            break;
        std::vector<std::pair<long, std::string>> keys;
        for (const auto& [frame, v] : value.items()) {
            char* end        = nullptr;
            const long number = std::strtol(frame.c_str(), &end, 10);
            if (frame.empty() || *end != '\0') {
                error = format("key '{}' is not a frame number", frame);
                return false;
            }
            if (!component(v))
                break;
            keys.emplace_back(number, value_text(v));
        }
        if (keys.size() != value.size())
            break;
        std::sort(keys.begin(), keys.end());
        std::vector<std::string> parts;
        for (const auto& [frame, v] : keys)
            parts.push_back(format("{}:{}", frame, v));
        text = OIIO::Strutil::join(parts, ",");
        return true;
    }
    case ShotValueKind::Text:
    case ShotValueKind::Path:
    case ShotValueKind::FileOrName:
        if (!value.is_string())
            break;
        text = value.get<std::string>();
        return true;
    }
    static const char* expected[] = {
        "a number", "a number or keyframes {\"frame\": number, ...}",
        "[x, y] or keyframes {\"frame\": [x, y], ...}", "a string", "a file name",
        "a file or channel name",
    };
    error = format("expected {}, not {}", expected[int(kind)], value.type_name());
    return false;
}

/// Whole numbers as JSON integers ("blades": 6, not 6.0).
json number_json(double value)
{
    if (value == std::floor(value) && std::abs(value) < 1e15)
        return json(int64_t(value));
    return json(value);
}

json to_json(const std::string& text, ShotValueKind kind)
{
    switch (kind) {
    case ShotValueKind::Number: return number_json(std::stod(text));
    case ShotValueKind::Text:
    case ShotValueKind::Path:
    case ShotValueKind::FileOrName: return text;
    case ShotValueKind::Keyframes:
    case ShotValueKind::Point: break;
    }
    const int arity = kind == ShotValueKind::Point ? 2 : 1;
    Keyframes keys;
    std::string error;
    Keyframes::parse("", text, arity, -1e300, 1e300, keys, error);
    auto value = [&](const Keyframes::Key& key) {
        return arity == 1 ? number_json(key.value[0])
                          : json::array({ number_json(key.value[0]), number_json(key.value[1]) });
    };
    if (!keys.animated())
        return value(keys.keys().front());
    json object = json::object();
    for (const Keyframes::Key& key : keys.keys())
        object[std::to_string(key.frame)] = value(key);
    return object;
}

const ShotSetting* find_setting(const std::string& section, const std::string& key)
{
    for (const ShotSetting& s : shot_settings())
        if (section == s.section && key == s.key)
            return &s;
    return nullptr;
}

bool is_section(const std::string& name)
{
    for (const ShotSetting& s : shot_settings())
        if (name == s.section)
            return true;
    return false;
}

bool read_inputs(const json& value, const std::string& directory, Shot& shot,
                 std::string& error)
{
    if (!value.is_array()) {
        error = format("inputs: expected a list of file names, not {}", value.type_name());
        return false;
    }
    if (value.empty()) {
        error = "inputs: the list is empty: name at least one input file";
        return false;
    }
    std::vector<std::string> inputs;
    for (const json& item : value) {
        if (!item.is_string()) {
            error = format("inputs: expected file names, not {}", item.type_name());
            return false;
        }
        const std::string path = resolve(item.get<std::string>(), directory);
        if (!is_frame_pattern(path) && !OIIO::Filesystem::exists(path)) {
            error = format("inputs: {}: no such file", path);
            return false;
        }
        inputs.push_back(path);
    }
    shot.inputs = std::move(inputs);
    return true;
}

bool read_document(const json& doc, const std::string& directory, Shot& shot,
                   std::string& error)
{
    if (!doc.is_object()) {
        error = format("expected a JSON object, not {}", doc.type_name());
        return false;
    }
    if (!doc.contains("version")) {
        error = "no \"version\": a .dof file starts with \"version\": 1";
        return false;
    }
    // Compared as the JSON number it is: a narrower integer would wrap
    // 4294967297 round to 1.
    const json& version = doc["version"];
    if (!version.is_number_integer()
        || (!version.is_number_unsigned() && version.get<int64_t>() < 1)) {
        error = "version: expected a whole number from 1";
        return false;
    }
    if (version.get<uint64_t>() > uint64_t(shot_file_version)) {
        error = format("version {} is newer than this defocus reads ({})", version.dump(),
                       shot_file_version);
        return false;
    }
    if (!doc.contains("inputs")) {
        error = "no \"inputs\": the scene's files";
        return false;
    }
    if (!read_inputs(doc["inputs"], directory, shot, error))
        return false;
    for (const auto& [section, body] : doc.items()) {
        if (section == "version" || section == "inputs")
            continue;
        if (!is_section(section)) {
            error = format("unknown key '{}'", section);
            return false;
        }
        if (!body.is_object()) {
            error = format("{}: expected an object, not {}", section, body.type_name());
            return false;
        }
        if (section == "camera" && body.contains("focus") && body.contains("focus_at")) {
            error = "camera: give focus or focus_at, not both";
            return false;
        }
        for (const auto& [key, value] : body.items()) {
            const std::string where = section + "." + key;
            const ShotSetting* setting = find_setting(section, key);
            if (!setting) {
                error = format("unknown key '{}'", where);
                return false;
            }
            std::string text;
            if (!to_text(value, setting->kind, text, error)) {
                error = where + ": " + error;
                return false;
            }
            if (setting->kind == ShotValueKind::Path
                || (setting->kind == ShotValueKind::FileOrName
                    && OIIO::Filesystem::exists(resolve(text, directory))))
                text = resolve(text, directory);
            if (!set_shot_setting(shot, setting->name, text, error, where))
                return false;
        }
    }
    return true;
}

/// The deepest nesting of arrays and objects in JSON text, outside
/// strings. A .dof nests three deep; JSON nested 100000 deep is parsed
/// without recursion, but copying or walking it recurses past the stack.
int nesting_depth(const std::string& text)
{
    int depth = 0, deepest = 0;
    bool in_string = false, escaped = false;
    for (const char c : text) {
        if (in_string) {
            if (escaped)
                escaped = false;
            else if (c == '\\')
                escaped = true;
            else if (c == '"')
                in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            deepest = std::max(deepest, ++depth);
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
    return deepest;
}

}  // namespace

bool parse_shot(const std::string& text, const std::string& directory,
                const std::string& source, Shot& shot, std::string& error)
{
    constexpr int deepest = 32;
    if (nesting_depth(text) > deepest) {
        error = OIIO::Strutil::fmt::format("{}: arrays and objects nested more than {} deep: "
                                           "not a scene file", source, deepest);
        return false;
    }
    json doc;
    try {
        doc = json::parse(text);
    } catch (const json::exception& e) {  // syntax, and numbers out of range
        // e.what() is "[json.exception.parse_error.101] parse error at line
        // L, column C: ..."; the bracketed id means nothing to a user.
        std::string what = e.what();
        const size_t id_end = what.find("] ");
        error = format("{}: not valid JSON: {}", source,
                       id_end == std::string::npos ? what : what.substr(id_end + 2));
        return false;
    }
    Shot loaded = shot;
    if (!read_document(doc, directory, loaded, error)) {
        error = source + ": " + error;
        return false;
    }
    shot = std::move(loaded);
    return true;
}

bool load_shot(const std::string& filename, Shot& shot, std::string& error)
{
    std::string text;
    if (!OIIO::Filesystem::is_regular(filename)) {
        error = filename + ": no such file";
        return false;
    }
    // A scene file is a few KB; parsing 100 MB of JSON takes seconds and
    // gigabytes before it can say what is wrong.
    constexpr uint64_t largest = uint64_t(16) << 20;
    if (const uint64_t size = OIIO::Filesystem::file_size(filename); size > largest) {
        error = OIIO::Strutil::fmt::format("{}: {} MB is too large for a .dof scene file "
                                           "(at most 16 MB)",
                                           filename, size >> 20);
        return false;
    }
    if (!OIIO::Filesystem::read_text_file(filename, text)) {
        error = filename + ": cannot read";
        return false;
    }
    return parse_shot(text, OIIO::Filesystem::parent_path(filename), filename, shot, error);
}

std::string shot_to_json(const Shot& shot, const std::string& directory)
{
    json doc = json::object();
    doc["version"] = shot_file_version;
    json inputs    = json::array();
    for (const std::string& input : shot.inputs)
        inputs.push_back(relative_to(input, directory));
    doc["inputs"] = inputs;
    // Only what was given: a default left out stays a default, so that a
    // render's own camera (camera_from_file) still applies when it is loaded.
    for (const ShotSetting& s : shot_settings()) {
        if (!is_given(shot, s.name))
            continue;
        std::string text = shot_setting(shot, s.name);
        if (s.kind == ShotValueKind::Path
            || (s.kind == ShotValueKind::FileOrName && OIIO::Filesystem::exists(text)))
            text = relative_to(text, directory);
        doc[s.section][s.key] = to_json(text, s.kind);
    }
    return doc.dump(4) + "\n";
}

bool save_shot(const Shot& shot, const std::string& filename, std::string& error)
{
    return write_text_atomic(filename, shot_to_json(shot, OIIO::Filesystem::parent_path(filename)),
                             error);
}

}  // namespace defocus
