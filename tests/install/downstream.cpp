// Links the installed library and loads the colour config it finds by
// itself (the shipped one, as the installed package names it); prints the
// path it loaded.
#include <cstdio>
#include <cstdlib>

#include <defocus/color/color.h>

int main()
{
    defocus::ColorManagement color;
    std::string error;
    if (!color.load("", error)) {
        std::fprintf(stderr, "%s\n", error.c_str());
        return 1;
    }
    std::printf("loaded %s\n", color.path().c_str());
    return 0;
}
