# Sourced by sanitize.sh and fuzz.sh: the clang build both use,
# build-sanitize/, with AddressSanitizer and UndefinedBehaviorSanitizer, the
# suite and the libFuzzer harnesses. Line tables are all the sanitizers'
# reports print, and cost less to build than full debug information.
sanitized_build=build-sanitize

configure_sanitized_build() {
    cmake -S . -B "$sanitized_build" -DCMAKE_CXX_COMPILER=clang++ \
        -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
        -DDEFOCUS_SANITIZE=ON -DDEFOCUS_FUZZ=ON -DBUILD_TESTING=ON -DDEFOCUS_BUILD_BENCHMARKS=OFF
}
