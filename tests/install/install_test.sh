#!/usr/bin/env bash
# Installs the build into a fresh prefix, as `cmake --install --prefix`
# does for a user, then checks that the installed tools run from there
# (relative RPATHs, the shipped config beside them), that the docs are
# installed, and that another project finds and links the package through
# CMake and through pkg-config; the Python package, man pages and bash
# completion are installed and work from there.
#   install_test.sh BUILD_DIR SOURCE_DIR SCRATCH_DIR
set -euo pipefail
build=$1 source=$2 scratch=$3
rm -rf "$scratch" && mkdir -p "$scratch"
prefix=$scratch/prefix
cmake --install "$build" --prefix "$prefix" > /dev/null

fail() { echo "FAILED: $*"; exit 1; }
for doc in README.md LICENSE; do
    [ -f "$prefix/share/doc/defocus/$doc" ] || fail "$doc not installed as documentation"
done
# OpenColorIO is looked for where the build found it, as a hint, not at a
# path fixed in the source.
grep -q "PATHS /usr/share/cmake" "$prefix"/lib*/cmake/defocus/defocusConfig.cmake \
    && fail "the package config hard-codes /usr/share/cmake"
runpath=$(readelf -d "$prefix/bin/defocus" | grep -E 'RUNPATH|RPATH' || true)
case $runpath in *'$ORIGIN'*) ;; *) fail "defocus has no \$ORIGIN-relative RPATH: $runpath" ;; esac

"$build/bin/make_example_scene" "$scratch/scene.exr" --width 160 --height 90 > /dev/null
log=$(env -u OCIO "$prefix/bin/defocus" "$scratch/scene.exr" -o "$scratch/out.exr" \
      --focal 50 --fstop 1.8 --focus 4 -v)
grep -q "config $prefix/share/defocus/config.ocio (shipped)" <<< "$log" \
    || fail "the installed defocus did not use the installed config: $log"
# Run as a user runs it: found through PATH, and through a symbolic link
# elsewhere (the loader then names the program "defocus", or the link).
mkdir -p "$scratch/links"
ln -s "$prefix/bin/defocus" "$scratch/links/defocus"
for how in "env PATH=$prefix/bin:$PATH defocus" "$scratch/links/defocus"; do
    log=$(cd "$scratch" && env -u OCIO $how scene.exr -o out.exr --focal 50 --fstop 1.8 --focus 4 -v)
    grep -q "config $prefix/share/defocus/config.ocio (shipped)" <<< "$log" \
        || fail "defocus run as '$how' did not find the installed config: $log"
done

cmake -S "$source/tests/install" -B "$scratch/downstream" -DCMAKE_PREFIX_PATH="$prefix" \
    > "$scratch/configure.log" 2>&1 || { cat "$scratch/configure.log"; fail "find_package(defocus)"; }
cmake --build "$scratch/downstream" > "$scratch/build.log" 2>&1 \
    || { cat "$scratch/build.log"; fail "building against the installed package"; }
# Another project's program, elsewhere, finds the config by itself.
env -u OCIO "$scratch/downstream/downstream" | grep -q "loaded $prefix/share/defocus/config.ocio" \
    || fail "a program built against the package does not find the installed config"

# pkg-config: the same program built by hand (static library: --static).
flags=$(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags --libs --static defocus) \
    || fail "pkg-config does not find defocus.pc"
config=$(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --variable=ocio_config defocus)
g++ -std=c++17 -DDEFOCUS_PACKAGE_OCIO_CONFIG="\"$config\"" \
    "$source/tests/install/downstream.cpp" -o "$scratch/downstream_pc" $flags \
    || fail "building with pkg-config --cflags --libs --static defocus"
env -u OCIO "$scratch/downstream_pc" | grep -q "loaded $prefix/share/defocus/config.ocio" \
    || fail "the program built with pkg-config did not find the installed config"

# The Python package, imported from the prefix (the module's RPATH finds
# the library, the config is the installed one). A sanitized build names
# its runtime in DEFOCUS_PYTHON_PRELOAD, for python3 to load first (leaks
# unchecked: CPython frees nothing at exit).
python_env=()
if [ -n "${DEFOCUS_PYTHON_PRELOAD:-}" ]; then
    python_env=(LD_PRELOAD="$DEFOCUS_PYTHON_PRELOAD" ASAN_OPTIONS=detect_leaks=0)
fi
if [ -f "$build/python/defocus/__init__.py" ]; then
    site=$prefix/lib/python3/dist-packages
    [ -f "$site/defocus/_defocus.pyi" ] || fail "the Python type stubs are not installed"
    env -u OCIO "${python_env[@]}" PYTHONPATH="$site" /usr/bin/python3 -c "
import defocus, numpy, sys
assert defocus.__file__.startswith('$site'), defocus.__file__
out = defocus.render(defocus.Shot(inputs=['$scratch/scene.exr'], focal=50, fstop=1.8, focus=4))
assert out.shape[2] == 4 and numpy.isfinite(out).all()
" || fail "the installed Python package does not render"
fi

if command -v help2man > /dev/null; then
    for tool in defocus layerize; do
        [ -s "$prefix/share/man/man1/$tool.1" ] || fail "man page $tool.1 not installed"
    done
fi
if [ -f "$build/bin/defocus-submit" ]; then
    env "${python_env[@]}" "$prefix/bin/defocus-submit" --version | grep -q "^defocus-submit " \
        || fail "the installed defocus-submit does not find its Python package"
fi
for tool in defocus layerize; do
    [ -s "$prefix/share/bash-completion/completions/$tool" ] \
        || fail "bash completion for $tool not installed"
done
echo "install test passed"
