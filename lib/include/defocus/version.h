// The library's version, as its tools and Python module report it.
#pragma once

namespace defocus {

/// "MAJOR.MINOR.PATCH", the project's version.
const char* version();

}  // namespace defocus
