// The memory one frame's images may take (--memory-limit). Files declare
// their own sizes, and a damaged or hostile header can declare terabytes:
// the reader and the layering check each allocation a file asks for
// against the limit before making it.
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>

namespace defocus {

class MemoryLimit {
public:
    /// The default: half the machine's physical memory.
    MemoryLimit() = default;
    explicit MemoryLimit(size_t bytes) : m_bytes(bytes) {}

    /// Parses a size such as "12G", "512M", "1.5T" or a number of bytes.
    /// On failure sets `error` naming `option` and returns false.
    static bool parse(const std::string& option, const std::string& text, MemoryLimit& limit,
                      std::string& error);
    /// The text parse() reads back to the same limit; "" for the default.
    std::string to_string() const;

    size_t bytes() const;
    /// Whether `bytes` more fit, beside what is spent already.
    bool allows(double bytes) const
    {
        return m_process + m_spent + bytes <= double(this->bytes());
    }
    /// The same limit with `bytes` of it held by the process itself (its
    /// code and libraries, what it holds beside the frames: a tool counts
    /// its resident memory before rendering), so that the limit bounds the
    /// process's peak.
    MemoryLimit beside_process(double bytes) const
    {
        MemoryLimit less = *this;
        less.m_process = bytes;
        return less;
    }
    /// What is left for the frames beside the process itself.
    double for_frames() const { return std::max(0.0, double(this->bytes()) - m_process); }
    /// The same limit with `bytes` more of it taken (by another input of
    /// the frame): what is left for the rest.
    MemoryLimit spent(double bytes) const
    {
        MemoryLimit less = *this;
        less.m_spent += bytes;
        return less;
    }
    /// "<what> needs 800 GB, more than the memory limit of 12 GB
    /// (--memory-limit)", and what other inputs and the process itself
    /// took when they took some.
    std::string exceeded(const std::string& what, double bytes) const;

private:
    size_t m_bytes = 0;      ///< 0: the default
    double m_process = 0.0;  ///< held by the process itself
    double m_spent = 0.0;    ///< taken already, of the limit, by the frame's other inputs
};

/// The bytes of `pixels` pixels of `channels` floats, as the checks
/// against the limit count them (in double: a hostile size cannot overflow).
inline double float_bytes(double pixels, int channels)
{
    return pixels * channels * sizeof(float);
}

}  // namespace defocus
