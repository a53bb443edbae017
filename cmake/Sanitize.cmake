# DEFOCUS_SANITIZE: every target is built with AddressSanitizer (memory
# errors, leaks) and UndefinedBehaviorSanitizer, and any finding stops the
# program (-fno-sanitize-recover) so a test cannot pass over it.
#
# DEFOCUS_FUZZ builds the same way plus the libFuzzer harnesses, and the
# library with libFuzzer's coverage instrumentation, so the harnesses find
# memory errors as well as crashes. With DEFOCUS_SANITIZE too, one build
# serves both the sanitized suite and the fuzzers (scripts/sanitize.sh,
# scripts/fuzz.sh).
#
# Programs built elsewhere (Debian's oiiotool and python3) that load our
# plugin need the sanitizer runtime loaded first: DEFOCUS_SANITIZER_PRELOAD
# is what to put in LD_PRELOAD for them, libraries separated by colons
# (empty when not sanitizing).

set(DEFOCUS_SANITIZER_PRELOAD "")
set(DEFOCUS_FUZZ_COVERAGE_FLAGS "")
set(DEFOCUS_PYTHON_SANITIZER_ENV "")
set(DEFOCUS_SANITIZER_FLAGS "")
if(DEFOCUS_SANITIZE OR DEFOCUS_FUZZ)
    set(DEFOCUS_SANITIZER_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=all
                                -fno-omit-frame-pointer)
    add_compile_options(${DEFOCUS_SANITIZER_FLAGS})
    add_link_options(${DEFOCUS_SANITIZER_FLAGS})
    if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
        # clang links its runtime statically into executables by default; a
        # shared runtime lets the plugin share it with its host. (A fuzz
        # build alone keeps the static one; beside the suite, the harnesses
        # need the shared one preloaded: scripts/fuzz.sh.)
        set(_runtime libclang_rt.asan-x86_64.so)
    else()
        set(_runtime libasan.so)
    endif()
    execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=${_runtime}
                    OUTPUT_VARIABLE DEFOCUS_SANITIZER_PRELOAD OUTPUT_STRIP_TRAILING_WHITESPACE)
    if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang" AND DEFOCUS_SANITIZE)
        # The shared runtime is not where the loader looks: the programs
        # are told where it is.
        get_filename_component(_runtime_dir ${DEFOCUS_SANITIZER_PRELOAD} DIRECTORY)
        add_link_options(-shared-libasan -Wl,-rpath,${_runtime_dir})
    endif()
    # With the runtime loaded before libstdc++ (python3 does not link it),
    # ASan cannot find the __cxa_throw it intercepts and aborts at the first
    # exception: libstdc++ goes in front too.
    execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=libstdc++.so.6
                    OUTPUT_VARIABLE _libstdcxx OUTPUT_STRIP_TRAILING_WHITESPACE)
    string(APPEND DEFOCUS_SANITIZER_PRELOAD ":${_libstdcxx}")
    # The environment python3 needs to load the sanitized module (the
    # Python tests, defocus-submit). Leaks are not checked there: CPython
    # frees nothing at exit, and the numpy and OpenImageIO objects a script
    # still holds then are never destroyed; their stacks end in Python frames
    # the unwinder cannot walk, so no suppression can name them. The
    # library's own leaks are checked by the C++ suites, which run the same
    # code.
    set(DEFOCUS_PYTHON_SANITIZER_ENV
        "LD_PRELOAD=${DEFOCUS_SANITIZER_PRELOAD}"
        "ASAN_OPTIONS=detect_leaks=0:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1")
endif()

if(DEFOCUS_FUZZ)
    if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
        message(FATAL_ERROR "DEFOCUS_FUZZ needs clang (libFuzzer): "
                            "configure with -DCMAKE_CXX_COMPILER=clang++")
    endif()
    # Coverage feedback from the library too (lib/CMakeLists.txt), not only
    # the harnesses. The tests, which link the same library, carry it: the
    # edge counters alone cost them little, where fuzzer-no-link's
    # comparison tracing made them 2.5-3 times slower.
    set(DEFOCUS_FUZZ_COVERAGE_FLAGS -fsanitize-coverage=inline-8bit-counters,pc-table)
endif()
