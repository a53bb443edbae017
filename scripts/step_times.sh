# Sourced by the scripts CI runs. `timed NAME COMMAND...` runs COMMAND and
# notes how long it took; on exit the script prints its notes in one line,
# also appended to the file $DEFOCUS_STEP_TIMES names when it is set (.ci/run
# prints that file at its end).
step_times=()
step_script=$(basename "$0")

timed() {
    local name=$1 start=$SECONDS status=0
    shift
    "$@" || status=$?
    step_times+=("$name $((SECONDS - start)) s")
    return $status
}

print_step_times() {
    local line="$step_script:"
    for note in "${step_times[@]}"; do
        line+=" $note,"
    done
    line="${line%,}"
    echo "$line"
    if [ -n "${DEFOCUS_STEP_TIMES:-}" ]; then
        echo "$line" >>"$DEFOCUS_STEP_TIMES"
    fi
}
trap print_step_times EXIT
