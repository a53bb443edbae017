#!/usr/bin/env bash
# Installs the build into a fresh prefix, as `cmake --install --prefix`
# does for a user, then checks that the installed tools run from there
# (relative RPATHs, the shipped config beside them), that the docs are
# installed, and that another CMake project finds and links the package.
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
grep -q "config $prefix/bin/../share/defocus/config.ocio (shipped)" <<< "$log" \
    || fail "the installed defocus did not use the installed config: $log"

cmake -S "$source/tests/install" -B "$scratch/downstream" -DCMAKE_PREFIX_PATH="$prefix" \
    > "$scratch/configure.log" 2>&1 || { cat "$scratch/configure.log"; fail "find_package(defocus)"; }
cmake --build "$scratch/downstream" > "$scratch/build.log" 2>&1 \
    || { cat "$scratch/build.log"; fail "building against the installed package"; }
"$scratch/downstream/downstream" | grep -q "loaded $prefix/share/defocus/config.ocio" \
    || fail "defocus_OCIO_CONFIG does not name the installed config"
echo "install test passed"
