// What every harness asserts beyond "no crash": a refusal always says why.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

namespace defocus_fuzz {

/// Stops the run as a finding when `holds` is false.
inline void require(bool holds, const char* what, const std::string& detail = "")
{
    if (!holds) {
        std::fprintf(stderr, "finding: %s %s\n", what, detail.c_str());
        std::abort();
    }
}

/// A refusal's message: one non-empty reason.
inline void require_reason(const std::string& error)
{
    require(!error.empty(), "a refusal without a reason");
}

}  // namespace defocus_fuzz
