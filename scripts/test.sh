#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine, builds defocus and runs the whole test
# suite. Tests that need ../shared/data skip with a message when it is absent.
# The suite's budget is 5 minutes on a 2-core machine (the manual's Architecture page): a
# longer check belongs in a benchmark or a nightly script.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/step_times.sh
timed packages bash scripts/install-deps.sh
timed build bash scripts/build.sh
data="${DEFOCUS_SHARED_DATA:-$(cd .. && pwd)/shared/data}"
[ -d "$data" ] || echo "note: no shared data at $data: the tests that need it are skipped"
cd build
start=$SECONDS
timed tests ctest --output-on-failure -j"$(nproc)"
budget=300
if [ $((SECONDS - start)) -gt $budget ]; then
    echo "warning: the suite took $((SECONDS - start)) s, over its budget of $budget s"
fi
# Why a test was skipped (CTest only says that it was).
grep -h "^SKIPPED:" Testing/Temporary/LastTest.log || true
