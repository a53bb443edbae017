#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine, builds defocus, generates the example
# layered scene and defocuses it.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh demo
bash examples/run_example.sh
