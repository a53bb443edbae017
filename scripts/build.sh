#!/usr/bin/env bash
# Configures and builds defocus (Release) in build/.
#   scripts/build.sh        everything: tools, plugin, tests, benchmark
#   scripts/build.sh demo   only what the example needs: the tools and plugin
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" = demo ]; then
    cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF \
        -DDEFOCUS_BUILD_BENCHMARKS=OFF
else
    cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=ON \
        -DDEFOCUS_BUILD_BENCHMARKS=ON
fi
cmake --build build -j"$(nproc)"
