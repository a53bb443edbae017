#include <defocus/error_line.h>

#include <OpenImageIO/strutil.h>

namespace defocus {

std::string error_line(const std::string& worded_or_not, SettingForm form, size_t limit)
{
    const std::string message = in_words(worded_or_not, form);
    std::string line;
    line.reserve(std::min(message.size(), 2 * limit));
    for (const char c : message) {
        const unsigned char u = static_cast<unsigned char>(c);
        if (c == '\n')
            line += "\\n";
        else if (c == '\t')
            line += "\\t";
        else if (u < 0x20 || u == 0x7f)
            line += OIIO::Strutil::fmt::format("\\x{:02x}", unsigned(u));
        else
            line += c;
    }
    if (line.size() <= limit)
        return line;
    const std::string cut = " ... ";
    const size_t keep = limit > cut.size() ? limit - cut.size() : 0;
    return line.substr(0, keep / 2) + cut + line.substr(line.size() - (keep - keep / 2));
}

std::string error_about(const std::string& file, const std::string& message)
{
    const std::string prefix = file + ": ";
    return OIIO::Strutil::starts_with(message, prefix) ? message : prefix + message;
}

}  // namespace defocus
