#include <defocus/shot/option_value.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include <OpenImageIO/strutil.h>

namespace defocus {

using OIIO::Strutil::fmt::format;

bool parse_number(const std::string& option, const std::string& text, double lo,
                  double hi, double& value, std::string& error)
{
    const char* begin = text.c_str();
    char* end         = nullptr;
    errno             = 0;
    const double v    = std::strtod(begin, &end);
    if (text.empty() || end == begin || *end != '\0' || errno == ERANGE
        || !std::isfinite(v)) {
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
