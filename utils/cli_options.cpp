#include "cli_options.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <regex>
#include <sstream>

#include <defocus/shot/option_value.h>
#include <defocus/version.h>

namespace defocus {

using OIIO::ArgParse;
using OIIO::cspan;

void add_version_option(ArgParse& ap, const char* program)
{
    ap.arg("--version").help("Print the version and exit")
        .action([&ap, program](cspan<const char*>) {
            OIIO::Strutil::print("{} {}\n", program, version());
            ap.abort();
        });
}

namespace {

/// What `ap` prints for --help. OIIO's ArgParse gives its options, and
/// its help, only through print_help(), to std::cout.
std::string help_text(const ArgParse& ap)
{
    std::stringstream help;
    std::streambuf* out = std::cout.rdbuf(help.rdbuf());
    ap.print_help();
    std::cout.rdbuf(out);
    return help.str();
}

/// The options `ap` lists in its help, as --help prints them.
std::vector<std::string> option_names(const ArgParse& ap)
{
    static const std::regex option("^ +(--?[a-z][-a-z0-9]*)");
    std::vector<std::string> names;
    std::smatch m;
    std::stringstream help(help_text(ap));
    for (std::string line; std::getline(help, line);)
        if (std::regex_search(line, m, option))
            names.push_back(m[1]);
    return names;
}

/// Where the help starts on an option's line of --help ("    --focus DIST
/// Focus ..."); npos on other lines.
size_t help_column(const std::string& line)
{
    static const std::regex option_line("^( +-\\S+(?: [^ ]+)* {2,})");
    std::smatch m;
    return std::regex_search(line, m, option_line) ? size_t(m[1].length()) : std::string::npos;
}

/// `line` cut into lines of at most `width` characters, the later ones
/// indented to where its text starts: after the option for an option's
/// line, else its own indent. No later line starts with '-', which would
/// read as an option (to the manual's and the completion's readers too).
std::string wrap_help_line(const std::string& line, size_t width)
{
    if (line.size() <= width)
        return line + "\n";
    const size_t column = help_column(line);
    const size_t indent = column != std::string::npos ? column : line.find_first_not_of(' ');
    if (indent == std::string::npos || indent + 20 > width)
        return line + "\n";
    const std::vector<std::string> words = OIIO::Strutil::splits(line.substr(indent), " ");
    std::vector<std::vector<std::string>> lines(1);
    size_t used = 0;
    for (const std::string& word : words) {
        if (!lines.back().empty() && indent + used + 1 + word.size() > width) {
            lines.emplace_back();
            used = 0;
            // Take the previous word along rather than start with a dash.
            if (word[0] == '-' && lines[lines.size() - 2].size() > 1) {
                std::vector<std::string>& previous = lines[lines.size() - 2];
                lines.back().push_back(previous.back());
                used = previous.back().size();
                previous.pop_back();
            }
        }
        used += (lines.back().empty() ? 0 : 1) + word.size();
        lines.back().push_back(word);
    }
    std::string out = line.substr(0, indent);
    for (size_t i = 0; i < lines.size(); ++i)
        out += (i ? std::string(indent, ' ') : "") + OIIO::Strutil::join(lines[i], " ") + "\n";
    return out;
}

/// The heading printed above a group's options, "" for the groups whose
/// heading the tool words itself (it shares it with its own options).
const char* option_group_heading(OptionGroup group)
{
    switch (group) {
    case OptionGroup::Sequences: return "Sequences:";
    case OptionGroup::Camera:
        return "Camera (DIST, N and MM take keyframes FRAME:VALUE,... for a focus pull):";
    case OptionGroup::Aperture: return "Aperture:";
    case OptionGroup::Scene: return "Scene:";
    default: return "";
    }
}

/// The lines of `help` with each option's help on its option's line.
/// OIIO 2.4's ArgParse wraps help at the width it reads from stdout, which
/// it reads unset when stdout is not a terminal: sometimes it wraps, at a
/// width of its own, indenting the rest a little past the help's column.
std::vector<std::string> unwrapped_help(const std::string& help)
{
    std::vector<std::string> lines;
    std::stringstream in(help);
    for (std::string line; std::getline(in, line);) {
        const size_t indent = line.find_first_not_of(' ');
        const size_t column = lines.empty() ? std::string::npos : help_column(lines.back());
        if (column != std::string::npos && indent != std::string::npos && indent >= column)
            lines.back() += " " + line.substr(indent);
        else
            lines.push_back(line);
    }
    return lines;
}

}  // namespace

int terminal_columns()
{
    struct winsize size = {};
    if (isatty(STDOUT_FILENO) && ioctl(STDOUT_FILENO, TIOCGWINSZ, &size) == 0 && size.ws_col > 0)
        return size.ws_col;
    const char* columns = std::getenv("COLUMNS");
    const int given = columns ? std::atoi(columns) : 0;
    return given > 0 ? given : 80;
}

std::string unknown_option_hint(const ArgParse& ap, const std::string& error)
{
    static const std::regex invalid("Invalid option \"(-[^\"]*)\"");
    std::smatch m;
    if (!std::regex_search(error, m, invalid))
        return error;
    // OIIO's own guess takes the first of equally near names (--focsu:
    // --focal before --focus); a swap of two letters is the likelier typo.
    const std::string plain = error.substr(0, size_t(m.position(0) + m.length(0)));
    const std::string given = m[1];
    std::string nearest;
    // Two letters swapped: the same letters in another order.
    auto letters = [](std::string s) {
        std::sort(s.begin(), s.end());
        return s;
    };
    if (OIIO::Strutil::starts_with(given, "--")) {
        size_t best = std::max<size_t>(2, given.size() / 3) + 1;  // farther is no typo
        for (const std::string& name : option_names(ap)) {
            const size_t d = OIIO::Strutil::edit_distance(given, name);
            if (d < best || (d == best && letters(name) == letters(given))) {
                best = d;
                nearest = name;
            }
        }
    }
    if (nearest.empty())
        return OIIO::Strutil::contains(error, "did you mean") ? error : plain + " (see --help)";
    return plain + ": did you mean " + nearest + "?";
}

void add_help_option(ArgParse& ap)
{
    ap.arg("--help").help("Print help message").action([&ap](cspan<const char*>) {
        const size_t width = size_t(std::max(terminal_columns(), 60) - 1);
        for (const std::string& line : unwrapped_help(help_text(ap)))
            OIIO::Strutil::print("{}", wrap_help_line(line, width));
        ap.abort();
    });
}

int parse_arguments(ArgParse& ap, int argc, const char* argv[])
{
    static const std::regex option_value("(--[a-z][a-z0-9-]*)=(.*)");
    std::vector<std::string> args;
    std::cmatch m;
    bool options_ended = false;
    for (int i = 0; i < argc; ++i) {
        // After a lone "--", as POSIX tools take it, every word is a file:
        // ArgParse takes words that begin with '-' as options, and
        // "./-name" is the same file.
        if (i > 0 && !options_ended && std::strcmp(argv[i], "--") == 0) {
            options_ended = true;
        } else if (options_ended) {
            args.emplace_back(argv[i][0] == '-' ? std::string("./") + argv[i] : argv[i]);
        } else if (i > 0 && std::regex_match(argv[i], m, option_value)) {
            args.push_back(m[1]);
            args.push_back(m[2]);
        } else {
            args.emplace_back(argv[i]);
        }
    }
    std::vector<const char*> pointers;
    for (const std::string& a : args)
        pointers.push_back(a.c_str());
    return ap.parse_args(int(pointers.size()), pointers.data());
}

std::function<void(cspan<const char*>)> ShotArguments::store_into(std::string& into)
{
    return [this, &into](cspan<const char*> argv) {
        m_given.push_back({ argv[0], "", argv[1] });
        into = argv[1];
    };
}

void ShotArguments::add_options(ArgParse& ap, OptionGroup group)
{
    if (*option_group_heading(group))
        ap.separator(option_group_heading(group));
    for (const ShotSetting& setting : shot_settings()) {
        if (setting.group != group)
            continue;
        if (setting.option)
            ap.arg(setting.option).help(setting.help).action(
                [this, &setting](cspan<const char*> argv) {
                    m_given.push_back({ argv[0], setting.name, argv[1] });
                });
        for (const SettingSwitch& on : setting.switches)
            ap.arg(on.flag).help(on.help).action([this, &setting, &on](cspan<const char*> argv) {
                m_given.push_back({ argv[0], setting.name, on.value });
            });
    }
}

void ShotArguments::add_threads(ArgParse& ap)
{
    ap.arg("--threads N").help("Worker threads (default: 0 = all cores)")
        .action(store_into(m_threads));
}

bool ShotArguments::apply(Shot& shot, std::string& error) const
{
    for (size_t i = 0; i < m_given.size(); ++i)
        for (size_t j = i + 1; j < m_given.size(); ++j) {
            const Given &a = m_given[i], &b = m_given[j];
            const bool same = a.setting.empty() ? a.option == b.option : a.setting == b.setting;
            if (!same || a.value == b.value)
                continue;
            error = a.option == b.option
                        ? OIIO::Strutil::fmt::format("{} given twice ('{}' and '{}'): give it once",
                                                     a.option, a.value, b.value)
                        : OIIO::Strutil::fmt::format("{} and {} contradict each other: give one",
                                                     a.option, b.option);
            return false;
        }
    for (const Given& g : m_given)
        if (!g.setting.empty()
            && !set_shot_setting(shot, g.setting, g.value, error, g.option))
            return false;
    return true;
}

bool ShotArguments::threads(int& threads, std::string& error) const
{
    return parse_whole_number("--threads", m_threads, 0, 1024, threads, error);
}

}  // namespace defocus
