#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang, with ASan + UBSan) in the build
# sanitize.sh uses, build-sanitize/ (after it, nothing is left to build),
# and runs each on its seed corpus in tests/fuzz/corpus for SECONDS
# (default 60), as many at once as there are cores (each harness runs on
# one). Inputs that grow coverage collect in build-sanitize/fuzz/corpus; a
# crash, hang, leak or over-budget allocation stops the run, is saved in
# build-sanitize/fuzz/findings/ and fails the script.
#   scripts/fuzz.sh [SECONDS] [HARNESS...]   harnesses: shot_file settings scene read
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/step_times.sh
source scripts/sanitized_build.sh
seconds="${1:-60}"
shift || true
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=(shot_file settings scene read)
timed packages bash scripts/install-deps.sh clang
configure_sanitized_build
timed build cmake --build "$sanitized_build" -j"$(nproc)" --target "${harnesses[@]/#/fuzz_}"
out="$sanitized_build/fuzz"
data="${DEFOCUS_SHARED_DATA:-$(cd .. && pwd)/shared/data}"
# The build's programs share clang's shared sanitizer runtime, which must
# be the first library loaded: libFuzzer links libstdc++ before it.
runtime=$(clang++ -print-file-name=libclang_rt.asan-x86_64.so)
export ASAN_OPTIONS="detect_leaks=1"
export LSAN_OPTIONS="suppressions=$PWD/tests/sanitizer/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
mkdir -p "$out/findings"

# Runs one harness: its log in $out/fuzz_HARNESS.log, its exit status in
# $out/fuzz_HARNESS.status.
fuzz() {
    local harness=$1
    local seeds=(tests/fuzz/corpus/"$harness")
    # The readers alone start from every file and scene file the others do.
    [ "$harness" = read ] && seeds+=(tests/fuzz/corpus/scene tests/fuzz/corpus/shot_file)
    # The whole Damaged corpus, when the shared data is here (the
    # repository keeps only its small files).
    if [ "$harness" = scene ] || [ "$harness" = read ] && [ -d "$data/openexr-images/Damaged" ]; then
        seeds+=("$data/openexr-images/Damaged")
    fi
    mkdir -p "$out/corpus/$harness"
    # -timeout: one input taking 10 s is a hang. -rss_limit_mb: the memory
    # the harness may use, above the 1 GB --memory-limit the scene harness
    # sets.
    local status=0
    LD_PRELOAD="$runtime" "$sanitized_build/bin/fuzz_$harness" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2560 \
        -max_len=65536 -print_final_stats=1 -artifact_prefix="$out/findings/$harness-" \
        "$out/corpus/$harness" "${seeds[@]}" 2>"$out/fuzz_$harness.log" || status=$?
    echo $status >"$out/fuzz_$harness.status"
}

# Every harness, as many at once as there are cores.
fuzz_all() {
    local running=0
    for harness in "${harnesses[@]}"; do
        if [ $running -ge "$(nproc)" ]; then
            wait -n
            running=$((running - 1))
        fi
        echo "== fuzz_$harness for ${seconds} s"
        fuzz "$harness" &
        running=$((running + 1))
    done
    wait
}

timed fuzzing fuzz_all
status=0
for harness in "${harnesses[@]}"; do
    echo "== fuzz_$harness"
    if [ "$(cat "$out/fuzz_$harness.status")" = 0 ]; then
        grep -E "^stat::(number_of_executed_units|peak_rss_mb)|^Done" "$out/fuzz_$harness.log" || true
    else
        status=1
        tail -n 60 "$out/fuzz_$harness.log"
    fi
done
exit $status
