#include <defocus/shot/option_value.h>

#include <charconv>
#include <cmath>

#include <OpenImageIO/strutil.h>

namespace defocus {

using OIIO::Strutil::fmt::format;

bool parse_number(const std::string& option, const std::string& text, double lo,
                  double hi, double& value, std::string& error)
{
    // Decimal only, all of the text: strtod also takes hex floats
    // ("0x1p3"), "inf", leading blanks and the locale's decimal point.
    const char* begin = text.data();
    const char* end   = begin + text.size();
    if (begin != end && *begin == '+' && begin + 1 != end && begin[1] != '-')
        ++begin;
    double v = 0.0;
    const auto [stop, status] = std::from_chars(begin, end, v, std::chars_format::general);
    if (text.empty() || status != std::errc() || stop != end || !std::isfinite(v)) {
        error = format("{}: '{}' is not a number", option, text);
        return false;
    }
    if (v < lo || v > hi) {
        error = format("{}: {} is out of range [{}, {}]", option, text, lo, hi);
        return false;
    }
    value = v;
    return true;
}

bool parse_whole_number(const std::string& option, const std::string& text, double lo,
                        double hi, int& value, std::string& error)
{
    double v = 0;
    if (!parse_number(option, text, lo, hi, v, error))
        return false;
    if (v != std::floor(v)) {
        error = format("{}: {} is not a whole number", option, text);
        return false;
    }
    value = int(v);
    return true;
}

}  // namespace defocus
