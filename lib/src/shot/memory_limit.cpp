#include <defocus/shot/memory_limit.h>

#include <algorithm>
#include <cctype>
#include <cmath>

#include <OpenImageIO/strutil.h>
#include <OpenImageIO/sysutil.h>

#include <defocus/shot/option_value.h>
#include <defocus/shot/setting_words.h>

namespace defocus {

namespace {

struct Unit {
    char suffix;
    double bytes;
};
constexpr Unit units[] = { { 'T', 1024.0 * 1024 * 1024 * 1024 },
                           { 'G', 1024.0 * 1024 * 1024 },
                           { 'M', 1024.0 * 1024 },
                           { 'K', 1024.0 } };

std::string readable(double bytes)
{
    // Units are of 1024: 1000 to 1023 of one are written whole, not as 1e+03.
    for (const Unit& unit : units)
        if (bytes >= unit.bytes) {
            const double count = bytes / unit.bytes;
            return count >= 999.5
                       ? OIIO::Strutil::fmt::format("{:.0f} {}B", count, unit.suffix)
                       : OIIO::Strutil::fmt::format("{:.3g} {}B", count, unit.suffix);
        }
    return OIIO::Strutil::fmt::format("{:.0f} bytes", bytes);
}

}  // namespace

bool MemoryLimit::parse(const std::string& option, const std::string& text, MemoryLimit& limit,
                        std::string& error)
{
    std::string number = text;
    double scale = 1.0;
    for (const Unit& unit : units)
        if (!text.empty() && std::toupper(static_cast<unsigned char>(text.back())) == unit.suffix) {
            number.pop_back();
            scale = unit.bytes;
        }
    // From 1 MB, below which no frame fits, to 1 PB.
    double value = 0.0;
    if (!parse_number(option, number, 1024.0 * 1024 / scale, 1024.0 * units[0].bytes / scale,
                      value, error)) {
        error = option + ": expected a size such as 12G, 512M or 1.5T, got '" + text + "'";
        return false;
    }
    limit = MemoryLimit(size_t(std::llround(value * scale)));
    return true;
}

std::string MemoryLimit::to_string() const
{
    if (m_bytes == 0)
        return "";
    for (const Unit& unit : units)
        if (m_bytes % size_t(unit.bytes) == 0)
            return OIIO::Strutil::fmt::format("{}{}", m_bytes / size_t(unit.bytes), unit.suffix);
    return OIIO::Strutil::fmt::format("{}", m_bytes);
}

size_t MemoryLimit::bytes() const
{
    if (m_bytes)
        return m_bytes;
    const size_t physical = OIIO::Sysutil::physical_memory();
    return physical ? physical / 2 : size_t(4) << 30;
}

std::string MemoryLimit::exceeded(const std::string& what, double bytes) const
{
    const double limit = double(this->bytes());
    if (m_spent <= 0.0 && m_process <= 0.0)
        return OIIO::Strutil::fmt::format("{} needs {}, more than the memory limit of {} ({})",
                                          what, readable(bytes), readable(limit),
                                          mention("memory-limit"));
    const std::string beside
        = m_process <= 0.0 ? "the frame's other inputs"
          : m_spent <= 0.0
              ? OIIO::Strutil::fmt::format("what the program itself holds ({})",
                                           readable(m_process))
              : OIIO::Strutil::fmt::format(
                  "the frame's other inputs and what the program itself holds ({})",
                  readable(m_process));
    return OIIO::Strutil::fmt::format(
        "{} needs {}, more than the {} the memory limit of {} ({}) leaves beside {}", what,
        readable(bytes), readable(std::max(0.0, limit - m_process - m_spent)), readable(limit),
        mention("memory-limit"), beside);
}

}  // namespace defocus
