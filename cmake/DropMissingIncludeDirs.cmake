# Debian 12's CMake configs for some dependencies list include directories
# that do not exist: OpenImageIO's lists /usr/include/opencv4 even without
# OpenCV's headers, and OpenColorIO's config, installed directly in
# /usr/share/cmake, computes its prefix as / and lists /include. CMake
# refuses a target with a missing include directory; the real headers are
# under /usr/include, which the compiler searches anyway.
function(defocus_drop_missing_include_dirs target)
    if(NOT TARGET ${target})
        return()
    endif()
    get_target_property(_includes ${target} INTERFACE_INCLUDE_DIRECTORIES)
    set(_existing)
    foreach(_dir IN LISTS _includes)
        if(EXISTS "${_dir}")
            list(APPEND _existing "${_dir}")
        endif()
    endforeach()
    set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_existing}")
endfunction()

defocus_drop_missing_include_dirs(OpenImageIO::OpenImageIO)
defocus_drop_missing_include_dirs(OpenColorIO::OpenColorIO)
