#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine, builds defocus and runs the whole test
# suite. Tests that need ../shared/data skip with a message when it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
data="${DEFOCUS_SHARED_DATA:-$(cd .. && pwd)/shared/data}"
[ -d "$data" ] || echo "note: no shared data at $data: the tests that need it are skipped"
cd build
ctest --output-on-failure -j"$(nproc)"
# Why a test was skipped (CTest only says that it was).
grep -h "^SKIPPED:" Testing/Temporary/LastTest.log || true
