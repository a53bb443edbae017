# Debian 12's OpenImageIO config lists /usr/include/opencv4 among the include
# directories of OpenImageIO::OpenImageIO even when OpenCV's headers are not
# installed, and CMake refuses a target with a missing include directory.
# Nothing here uses OpenCV: keep only the directories that exist.
if(TARGET OpenImageIO::OpenImageIO)
    get_target_property(_defocus_oiio_includes OpenImageIO::OpenImageIO
                        INTERFACE_INCLUDE_DIRECTORIES)
    set(_defocus_oiio_existing)
    foreach(_dir IN LISTS _defocus_oiio_includes)
        if(EXISTS "${_dir}")
            list(APPEND _defocus_oiio_existing "${_dir}")
        endif()
    endforeach()
    set_target_properties(OpenImageIO::OpenImageIO PROPERTIES
        INTERFACE_INCLUDE_DIRECTORIES "${_defocus_oiio_existing}")
endif()
