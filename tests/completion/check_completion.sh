#!/usr/bin/env bash
# Bash completion of the tools, as bash-completion runs it: options from
# the tool's --help, names for options that take one, .exr/.dof files.
#   check_completion.sh COMPLETION_FILE BIN_DIR SCRATCH_DIR
set -o pipefail
script=$1 bin=$(cd "$2" && pwd) scratch=$3
fail() { echo "FAILED: $*"; exit 1; }
system=/usr/share/bash-completion/bash_completion
[ -f "$system" ] || { echo "SKIPPED: bash-completion is not installed"; exit 77; }
# bash_completion reads unset variables: not under set -u.
source "$system"
source "$script"
export PATH=$bin:$PATH
rm -rf "$scratch" && mkdir -p "$scratch" && cd "$scratch" || exit 1
touch shot.exr shot.dof notes.txt

complete_line() {  # completes the last word of "$@", prints the candidates
    COMP_WORDS=("$@")
    COMP_CWORD=$(($# - 1))
    COMP_LINE="$*"
    COMP_POINT=${#COMP_LINE}
    COMPREPLY=()
    _defocus "$1" "${COMP_WORDS[COMP_CWORD]}" "${COMP_WORDS[COMP_CWORD - 1]}"
    printf '%s\n' "${COMPREPLY[@]}" | sort | tr '\n' ' '
}
expect() {  # expect WANT COMMAND WORDS...
    local want=$1; shift
    local got
    got=$(complete_line "$@")
    [ "$got" = "$want " ] || fail "'$*' completed to '$got', expected '$want'"
}
expect "--fstop" defocus --fst
expect "--focus --focus-at --focus-at-radius --focus-tilt" defocus --focus
expect "--info" layerize --inf
expect "polygon" defocus --aperture pol
expect "bounded exact" defocus --spread ""
expect "half" defocus -d h
expect "shot.dof shot.exr" defocus sh
expect "" defocus --fstop ""
expect "--chunk --chunk-size" defocus-submit --chun
expect "--dry-run" defocus-submit --dry
echo "completion test passed"
