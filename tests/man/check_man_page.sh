#!/usr/bin/env bash
# Checks a tool's man page against its --help and --version: every option
# --help lists is documented, with its help text, and the version matches.
#   check_man_page.sh TOOL MAN_PAGE
set -euo pipefail
tool=$1 page=$2
fail() { echo "FAILED: $page: $*"; exit 1; }
[ -s "$page" ] || fail "missing"
# The page as text: roff escapes and font changes removed.
text=$(sed -E 's/\\-/-/g; s/\\f(\[[A-Z]*\]|[BIRP])//g; s/\\[,\/]//g; s/\\\(aq/'"'"'/g' "$page")
help=$("$tool" --help)
options=$(sed -nE 's/^ +(-[-a-z0-9]+).*/\1/p' <<< "$help")
[ -n "$options" ] || fail "$tool --help lists no options"
count=0
while read -r option; do
    grep -qF -- "$option" <<< "$text" || fail "does not document $option"
    # The first words of the option's help, as --help prints them.
    words=$(sed -nE "s/^ +$option( [^ ]+)? {2,}([^ ].{0,30}).*/\2/p" <<< "$help" | head -1)
    [ -z "$words" ] || grep -qF -- "$words" <<< "$text" || fail "$option: help '$words' missing"
    count=$((count + 1))
done <<< "$options"
# Every form of the command --help shows ("Usage: ...", "or: ...") is in
# the synopsis, where man readers look for it.
synopsis=$(sed -n '/^\.SH SYNOPSIS/,/^\.SH DESCRIPTION/p' <<< "$text")
name=$(basename "$tool")
usage=$(sed -n '/^Usage:/,/^$/p' <<< "$help")
forms=$(sed -nE "s/^ *(Usage:|or:|) +$name +([^ ]+).*/\\2/p" <<< "$usage")
[ -n "$forms" ] || fail "$tool --help shows no usage"
while read -r form; do
    grep -qF -- "$form" <<< "$synopsis" || fail "synopsis lacks the form '$form ...'"
done <<< "$forms"
version=$("$tool" --version)
grep -qF "\"$version\"" "$page" || fail "is not of $version"
echo "$page: $count options, $version: matches --help"
