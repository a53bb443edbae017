#include "python_errors.h"

#include <algorithm>
#include <regex>

#include <OpenImageIO/strutil.h>

#include <defocus/error_line.h>
#include <defocus/shot/shot.h>

namespace defocus_python {

using namespace defocus;
namespace Strutil = OIIO::Strutil;

namespace {

/// A setting's value as a Python literal: a number, a pixel (x, y), a
/// bool, or quoted text.
std::string python_literal(const ShotSetting& setting, const std::string& value)
{
    if (setting.kind == ShotValueKind::Point)
        return "(" + Strutil::replace(value, ",", ", ") + ")";
    if (setting.kind == ShotValueKind::Switch)
        return value == "on" ? "True" : "False";
    return Strutil::string_is<double>(value) ? value : "\"" + value + "\"";
}

}  // namespace

/// The library's message with each setting's option named as its Python
/// keyword: "--focus-at X,Y" reads "focus_at=X,Y", "--aperture polygon"
/// reads 'aperture="polygon"'. A word after an option is its value when
/// the setting takes it, or a placeholder when in capitals; else the
/// option stands alone ("--aov applies ..." reads "aov applies ...").
std::string python_words(const std::string& message)
{
    static const std::regex option(R"(--([a-z][a-z0-9-]*)( ([A-Za-z0-9:,.+-]*[A-Za-z0-9]))?)");
    std::string out;
    auto last = message.cbegin();
    for (std::sregex_iterator it(message.begin(), message.end(), option), end; it != end;
         ++it) {
        const std::smatch& m = *it;
        const auto setting = std::find_if(shot_settings().begin(), shot_settings().end(),
                                          [&](const ShotSetting& s) { return m[1] == s.name; });
        if (setting == shot_settings().end())
            continue;
        out.append(last, m[0].first);
        out += Strutil::replace(m[1].str(), "-", "_", true);
        const std::string word = m[3];
        Shot scratch;
        std::string ignored;
        if (m[2].matched && set_shot_setting(scratch, setting->name, word, ignored))
            out += "=" + python_literal(*setting, word);
        else if (m[2].matched && Strutil::upper(word) == word)
            out += "=" + word;
        else
            out += m[2].str();
        last = m[0].second;
    }
    out.append(last, message.cend());
    return out;
}

Error::Error(const std::string& message)
    : std::runtime_error(error_line(python_words(message)))
{
}

void check(bool ok, const std::string& error)
{
    if (!ok)
        throw Error(error);
}

}  // namespace defocus_python
