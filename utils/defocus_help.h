// The words of the defocus command's --help.
#pragma once

#include <OpenImageIO/argparse.h>

namespace defocus {

/// Gives `ap` the command's intro, usage, description, examples and -h.
void describe_defocus(OIIO::ArgParse& ap);

}  // namespace defocus
