#include <defocus/version.h>

namespace defocus {

const char* version()
{
    return DEFOCUS_VERSION;
}

}  // namespace defocus
