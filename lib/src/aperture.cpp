#include <defocus/aperture.h>

namespace defocus {

bool parse_aperture(const std::string& name, Aperture& aperture)
{
    if (name != "box")
        return false;
    aperture = Aperture::Box;
    return true;
}

const char* aperture_name(Aperture) { return "box"; }

}  // namespace defocus
