// Internal: enum values by name.
#pragma once

#include <cstddef>
#include <string>

namespace defocus {

/// The one of `values` that `name_of` calls `name`, into `value`; false
/// when none is.
template<typename Enum, size_t N>
bool parse_name(const std::string& name, const Enum (&values)[N], const char* (*name_of)(Enum),
                Enum& value)
{
    for (Enum v : values)
        if (name == name_of(v)) {
            value = v;
            return true;
        }
    return false;
}

}  // namespace defocus
