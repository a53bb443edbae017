# Startup time of the command-line tools.
#
# Debian's OpenImageIO pulls in about 260 shared libraries (GDAL, OpenVDB,
# DCMTK, ...). Before main() runs, the dynamic loader binds every symbol
# they reference by searching the global scope: the program, its direct
# dependencies, then theirs, breadth first. Large C++ libraries bind tens
# of thousands of symbols to themselves, and when they sit deep in that
# scope every lookup first probes the hundreds of libraries in front of
# them: 0.19 s before main() on this machine, for a program that does
# nothing but link OpenImageIO, longer than spreading the garden frame.
#
# Naming those libraries as direct dependencies of the tools moves them to
# the front of the scope (0.19 s -> 0.12 s). They are already loaded, as
# dependencies of OpenImageIO, so nothing new is loaded. The list is the
# libraries with the most lookups times their depth in the scope (measured
# with LD_DEBUG=bindings and LD_DEBUG=scopes). Moving a library changes
# which definition of a symbol wins only where two libraries export it:
# with nm over the whole closure, the only strong names exported twice are
# glibc's own, log4cplus's (also in DCMTK's oflog) and BLAS's (also in
# LAPACK), and none of those libraries is moved; vague-linkage C++
# symbols, also exported many times, are the same code wherever they win.
#
# The libraries are taken from what the installed OpenImageIO really loads
# (ldd), so a build against an OpenImageIO without them links nothing extra.

set(_defocus_heavy_libraries
    openvdb xerces-c gdal geos proj gdcmMSFF kmldom poppler dcmdata
    stdc\\+\\+ crypto glib-2.0 gio-2.0 mbedcrypto srt-gnutls nettle sqlite3 gnutls rttopo
    unistring netcdf pango-1.0 hdf5_serial nssutil3 spatialite harfbuzz ldap-2.5 codec2 Lerc
    mount)

function(_defocus_find_startup_libraries out)
    get_target_property(_oiio OpenImageIO::OpenImageIO LOCATION)
    find_program(_ldd ldd)
    if(NOT _oiio OR NOT _ldd)
        set(${out} "" PARENT_SCOPE)
        return()
    endif()
    execute_process(COMMAND ${_ldd} ${_oiio} OUTPUT_VARIABLE _loaded
                    RESULT_VARIABLE _status ERROR_QUIET)
    set(_found "")
    if(_status EQUAL 0)
        foreach(_name IN LISTS _defocus_heavy_libraries)
            # "\tlibgdal.so.32 => /lib/x86_64-linux-gnu/libgdal.so.32 (0x...)"
            if(_loaded MATCHES "lib${_name}[-.0-9]*\\.so[.0-9]* => ([^ \n]+) \\(")
                list(APPEND _found ${CMAKE_MATCH_1})
            endif()
        endforeach()
    endif()
    set(${out} "${_found}" PARENT_SCOPE)
endfunction()

if(NOT DEFINED CACHE{DEFOCUS_STARTUP_LIBRARIES})
    _defocus_find_startup_libraries(_libraries)
    set(DEFOCUS_STARTUP_LIBRARIES "${_libraries}" CACHE STRING
        "Libraries of OpenImageIO's closure linked first by the tools, for a faster start")
    list(LENGTH _libraries _count)
    message(STATUS "Tools link ${_count} of OpenImageIO's dependencies first, to start faster")
endif()

# Makes `target` name the startup libraries as its own dependencies: the
# tools, the Python module, and the test programs and scene generators,
# which the suite starts hundreds of times (test_cli once per test case,
# make_example_scene 51 times; test_unit's start 0.47 s -> 0.33 s).
function(defocus_fast_startup target)
    if(DEFOCUS_STARTUP_LIBRARIES)
        target_link_libraries(${target} PRIVATE
            "-Wl,--push-state,--no-as-needed" ${DEFOCUS_STARTUP_LIBRARIES} "-Wl,--pop-state")
    endif()
endfunction()
