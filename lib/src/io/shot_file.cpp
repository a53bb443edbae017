#include <defocus/io/shot_file.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include <nlohmann/json.hpp>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

#include <defocus/io/frames.h>
#include <defocus/io/image_output.h>

#include "util/file_identity.h"

namespace defocus {

// Objects keep their members in the file's order: a saved file reads in
// the order of shot_settings(). Such an object finds a key by a linear
// search, so large ones (keyframes) are built by appending (StrictDocument,
// to_json), never by inserting a key.
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
    case ShotValueKind::Switch:
        if (value.is_boolean())
            text = value.get<bool>() ? "on" : "off";
        else if (value.is_string())
            text = value.get<std::string>();
        else
            break;
        return true;
    }
    static const char* expected[] = {
        "a number", "a number or keyframes {\"frame\": number, ...}",
        "[x, y] or keyframes {\"frame\": [x, y], ...}", "a string", "a file name",
        "a file or channel name", "\"on\", \"off\", true or false",
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
    case ShotValueKind::FileOrName:
    case ShotValueKind::Switch: return text;
    case ShotValueKind::Keyframes:
    case ShotValueKind::Point: break;
    }
    const int arity = kind == ShotValueKind::Point ? 2 : 1;
    Keyframes keys;
    std::string error;
    Keyframes::parse("", text, arity, -1e300, 1e300, keys, error);
    auto value = [&](const Keyframes::Key& key) {
        return arity == 1 ? number_json(key.value[0])
                          : json::array({ number_json(key.value[0]),
                                                  number_json(key.value[1]) });
    };
    if (!keys.animated())
        return value(keys.keys().front());
    // The frames of keyframes increase, so no key is there already: they
    // are appended to the object's list of members, not inserted by its
    // linear search for the key (quadratic in the keys).
    json object = json::object();
    auto& members = static_cast<json::object_t::Container&>(
        object.get_ref<json::object_t&>());
    members.reserve(keys.keys().size());
    for (const Keyframes::Key& key : keys.keys())
        members.emplace_back(std::to_string(key.frame), value(key));
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
        || (version.is_number_unsigned() ? version.get<uint64_t>() < 1
                                         : version.get<int64_t>() < 1)) {
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

/// Builds the document from the parser's events, refusing what JSON
/// allows but a scene file must not hold: a key given twice in one object
/// (a parser keeps one, so the other would be dropped unseen) and a string
/// holding a NUL (cut short where the text reaches a C string). Members are
/// appended: inserting them one by one searches the object each time, which
/// made a million keyframes quadratic.
class StrictDocument final : public nlohmann::json_sax<json> {
public:
    /// The document, or false with `error` the first problem.
    static bool parse(const std::string& text, json& document, std::string& error)
    {
        StrictDocument builder;
        if (json::sax_parse(text, &builder) && builder.m_error.empty()) {
            document = std::move(builder.m_root);
            return true;
        }
        error = builder.m_error.empty() ? "not valid JSON" : builder.m_error;
        return false;
    }

    bool null() override { return add(nullptr); }
    bool boolean(bool value) override { return add(value); }
    bool number_integer(number_integer_t value) override { return add(value); }
    bool number_unsigned(number_unsigned_t value) override { return add(value); }
    bool number_float(number_float_t value, const string_t&) override { return add(value); }
    bool string(string_t& value) override { return no_nul(value) && add(std::move(value)); }
    bool binary(binary_t&) override { return refuse("binary values are not JSON"); }
    bool start_object(std::size_t) override { return open(json::object()); }
    bool key(string_t& key) override
    {
        if (!no_nul(key))
            return false;
        m_open.back().key = std::move(key);
        return true;
    }
    bool end_object() override
    {
        const std::string* twice = repeated_key(m_open.back().value->get_ref<const json::object_t&>());
        m_open.pop_back();
        return !twice || refuse(format("{}the key '{}' is given twice", where(), *twice));
    }
    bool start_array(std::size_t) override { return open(json::array()); }
    bool end_array() override
    {
        m_open.pop_back();
        return true;
    }
    bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception& e) override
    {
        // e.what() is "[json.exception.parse_error.101] parse error at line
        // L, column C: ..."; the bracketed id means nothing to a user.
        const std::string what = e.what();
        const size_t id_end = what.find("] ");
        return refuse("not valid JSON: "
                      + (id_end == std::string::npos ? what : what.substr(id_end + 2)));
    }

private:
    struct Open {
        json* value;      ///< an object or array being read
        std::string key;  ///< an object's key whose value comes next
    };

    /// Adds a value to the container being read; the address it has there.
    json* place(json&& value)
    {
        if (m_open.empty()) {
            m_root = std::move(value);
            return &m_root;
        }
        Open& parent = m_open.back();
        if (parent.value->is_array()) {
            parent.value->push_back(std::move(value));
            return &parent.value->back();
        }
        auto& members = static_cast<json::object_t::Container&>(
            parent.value->get_ref<json::object_t&>());
        members.emplace_back(parent.key, std::move(value));  // the key stays for where()
        return &members.back().second;
    }
    bool add(json&& value)
    {
        place(std::move(value));
        return true;
    }
    bool open(json&& container)
    {
        m_open.push_back({ place(std::move(container)), {} });
        return true;
    }

    /// A key the object holds twice, or null. Found among the keys sorted
    /// by their hashes (a million keyframes: a set of the keys took 0.5 s).
    static const std::string* repeated_key(const json::object_t& object)
    {
        std::vector<std::pair<size_t, const std::string*>> keys;
        keys.reserve(object.size());
        for (const auto& member : object)
            keys.emplace_back(std::hash<std::string>()(member.first), &member.first);
        std::sort(keys.begin(), keys.end(),
                  [](const auto& a, const auto& b) { return a.first < b.first; });
        for (size_t i = 0; i < keys.size(); ++i)
            for (size_t j = i + 1; j < keys.size() && keys[j].first == keys[i].first; ++j)
                if (*keys[j].second == *keys[i].second)
                    return keys[i].second;
        return nullptr;
    }

    /// "camera.focus: ", the keys leading to the value being read.
    std::string where() const
    {
        std::vector<std::string> path;
        for (const Open& open : m_open)
            if (open.value->is_object())
                path.push_back(open.key);
        return path.empty() ? "" : OIIO::Strutil::join(path, ".") + ": ";
    }
    bool no_nul(const std::string& text)
    {
        return text.find('\0') == std::string::npos
               || refuse(format("{}a string holds a NUL character (\\u0000)", where()));
    }
    bool refuse(const std::string& why)
    {
        if (m_error.empty())
            m_error = why;
        return false;
    }

    json m_root;
    std::vector<Open> m_open;  ///< the containers being read, outermost first
    std::string m_error;
};

/// The .dof files a shot refers to (inputs, depth, mask and PSF images
/// that are scene files themselves, as the OpenImageIO plugin opens
/// them), by name as given: what a scene file can nest.
std::vector<std::string> nested_shot_files(const Shot& shot)
{
    std::vector<std::string> nested;
    for (const std::string& file : shot_files(shot))
        if (OIIO::Strutil::iends_with(file, ".dof") && !is_frame_pattern(file)
            && OIIO::Filesystem::exists(file))
            nested.push_back(file);
    return nested;
}

/// Loads a .dof and walks the .dof files it refers to, and theirs, by file
/// identity (so that no name of a file, a link or a relative path, hides a
/// cycle): a scene file that reaches itself would have every program that
/// opens it through the plugin open it again until the stack overflows.
class ShotFileWalk {
public:
    bool load(const std::string& filename, Shot& shot, std::string& error)
    {
        const std::optional<FileIdentity> id = FileIdentity::of(filename);
        if (!id || !OIIO::Filesystem::is_regular(filename)) {
            error = filename + ": no such file";
            return false;
        }
        for (size_t i = 0; i < m_open.size(); ++i)
            if (m_open[i].id == *id) {
                std::vector<std::string> through;
                for (size_t j = i + 1; j < m_open.size(); ++j)
                    through.push_back(m_open[j].name);
                error = format("{}: refers to itself{}", m_open[i].name,
                               through.empty() ? "" : " through " + OIIO::Strutil::join(through, ", "));
                return false;
            }
        if (m_open.size() >= size_t(max_shot_file_nesting)) {
            std::vector<std::string> names;
            for (const Opened& o : m_open)
                names.push_back(o.name);
            error = format("{}: scene files nested more than {} deep ({} -> {})", names.front(),
                           max_shot_file_nesting, OIIO::Strutil::join(names, " -> "), filename);
            return false;
        }
        std::string text;
        if (!read_shot_text(filename, text, error)
            || !parse_shot(text, OIIO::Filesystem::parent_path(filename), filename, shot,
                           error))
            return false;
        if (m_walked.count(*id))
            return true;
        m_open.push_back({ filename, *id });
        for (const std::string& nested : nested_shot_files(shot)) {
            Shot inner;
            if (!load(nested, inner, error))
                return false;
        }
        m_open.pop_back();
        m_walked.insert(*id);
        return true;
    }

private:
    static bool read_shot_text(const std::string& filename, std::string& text,
                               std::string& error)
    {
        // A scene file is a few KB; parsing 100 MB of JSON takes seconds and
        // gigabytes before it can say what is wrong.
        constexpr uint64_t largest = uint64_t(64) << 20;
        if (const uint64_t size = OIIO::Filesystem::file_size(filename); size > largest) {
            error = format("{}: {} MB is too large for a .dof scene file (at most 64 MB)",
                           filename, size >> 20);
            return false;
        }
        if (!OIIO::Filesystem::read_text_file(filename, text)) {
            error = filename + ": cannot read";
            return false;
        }
        return true;
    }

    struct Opened {
        std::string name;
        FileIdentity id;
    };
    std::vector<Opened> m_open;       ///< the files being loaded, outermost first
    std::set<FileIdentity> m_walked;  ///< files whose nested files are checked
};

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
    if (!StrictDocument::parse(text, doc, error)) {
        error = format("{}: {}", source, error);
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
    ShotFileWalk walk;
    return walk.load(filename, shot, error);
}

std::string shot_to_json(const Shot& shot, const std::string& directory)
{
    json doc = json::object();
    doc["version"] = shot_file_version;
    json inputs = json::array();
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
