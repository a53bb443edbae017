#!/usr/bin/env bash
# Installs the Debian 12 packages defocus builds and tests with, if missing.
#   scripts/install-deps.sh        the build and the tests
#   scripts/install-deps.sh clang  also clang and its sanitizer and libFuzzer
#                                  runtimes (the sanitizer and fuzz builds)
set -euo pipefail

packages=(
    cmake g++ make pkg-config
    libopenimageio-dev openimageio-tools   # image I/O, ImageBuf, ArgParse, threads
    python3-openimageio                    # tests: Python opens .dof scenes via the plugin
    libopenexr-dev openexr                 # EXR reading (decode and damage checks in one pass)
    libdeflate-dev                         # faster inflating and deflating of zip-compressed EXR chunks
    zlib1g-dev                             # zlib.h: the tools answer zlib's compress2 with libdeflate
    libopencolorio-dev opencolorio-tools   # colour management, ociocheck
    nlohmann-json3-dev                     # .dof scene files (JSON)
    catch2                                 # tests
    pybind11-dev python3-dev               # the Python module (import defocus)
    python3-numpy python3-pytest           # its arrays, and its tests
    help2man                               # man pages made from --help
    python3-sphinx python3-myst-parser furo # the manual (docs/): Sphinx, Markdown pages, its theme
    bash-completion                        # tests: completion as bash runs it
    slurm-wlm munge                        # tests: defocus-submit on a one-node Slurm cluster
)
if [ "${1:-}" = clang ]; then
    packages+=(clang libclang-rt-14-dev)   # scripts/sanitize.sh and scripts/fuzz.sh
fi

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "Installing: ${missing[*]}"
    sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -q
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
