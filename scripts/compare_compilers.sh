#!/usr/bin/env bash
# Builds defocus with clang in build-clang/ beside the gcc build in build/
# (scripts/build.sh), checks that both make the same files
# (compare_outputs.sh), then runs bench_speed of each build in turn, RUNS
# times (default 3), and prints each measurement's median, gcc against
# clang, with the ratio. The kernels are compiled for AVX-512, AVX2 and
# the baseline by both compilers (util/simd.h), so clang should be within
# 1.15x of gcc.
#   scripts/compare_compilers.sh [RUNS] [bench_speed options...]
set -euo pipefail
cd "$(dirname "$0")/.."
runs="${1:-3}"
shift || true
[ -x build/bin/bench_speed ] || bash scripts/build.sh
cmake -S . -B build-clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Release \
    -DBUILD_TESTING=OFF >/dev/null
cmake --build build-clang -j"$(nproc)" --target bench_speed defocus_cli make_example_scene
bash scripts/compare_outputs.sh build build-clang | grep -v "^same" || true
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
for run in $(seq "$runs"); do
    for compiler in gcc clang; do
        dir=build
        [ "$compiler" = clang ] && dir=build-clang
        echo "run $run of $runs: $compiler" >&2
        "$dir/bin/bench_speed" --rounds 3 "$@" 2>/dev/null | grep " ms$" >>"$work/$compiler"
    done
done
python3 - "$work/gcc" "$work/clang" <<'EOF'
import re, statistics, sys
def medians(path):
    times = {}
    for line in open(path):
        m = re.match(r"(.*?)\s+([\d.]+) ms$", line.rstrip())
        if m:
            times.setdefault(m.group(1), []).append(float(m.group(2)))
    return {name: statistics.median(t) for name, t in times.items()}
gcc, clang = medians(sys.argv[1]), medians(sys.argv[2])
print(f"{'measurement':48s} {'gcc ms':>9s} {'clang ms':>9s}  clang/gcc")
for name, g in gcc.items():
    if name in clang:
        print(f"{name:48s} {g:9.1f} {clang[name]:9.1f}  {clang[name] / g:5.2f}x")
EOF
