#!/usr/bin/env python3
"""Checks that every C++ file under the given folders is short enough to
read in one sitting, and every function in them too:

    scripts/check_sizes.py [--file-lines N] [--function-lines N] FOLDER...

A function is a brace block whose opening line follows a signature (text
with parentheses that is not a control statement); its length runs from
that opening brace to the closing one, lambdas and all. Prints each file
or function over its limit and exits 1 if there is any."""
import argparse
import pathlib
import re
import sys

CONTROL = re.compile(r"^(if|for|while|switch|else|do|try|catch|return|namespace|struct|class|"
                     r"enum|union)\b")


def signature_before(lines, brace):
    """The signature whose body opens at line `brace` (a line holding only
    '{'), or None."""
    parts = []
    j = brace - 1
    while j >= 0:
        text = lines[j].strip()
        if not text or text.startswith("//") or text.endswith((";", "}", "{")):
            break
        parts.insert(0, text)
        j -= 1
    signature = " ".join(parts)
    if "(" not in signature or CONTROL.match(signature) or "=" in signature.split("(")[0]:
        return None
    return signature


def long_functions(lines, limit):
    i = 0
    while i < len(lines):
        signature = signature_before(lines, i) if lines[i].strip() == "{" else None
        if signature is None:
            i += 1
            continue
        depth, k = 0, i
        while k < len(lines):
            depth += lines[k].count("{") - lines[k].count("}")
            if depth <= 0:
                break
            k += 1
        if k - i + 1 > limit:
            yield i + 1, k - i + 1, signature
        i = k + 1


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--file-lines", type=int, default=700)
    parser.add_argument("--function-lines", type=int, default=80)
    parser.add_argument("folders", nargs="+")
    args = parser.parse_args()
    found = 0
    for folder in args.folders:
        for path in sorted(pathlib.Path(folder).rglob("*")):
            if path.suffix not in (".h", ".cpp"):
                continue
            lines = path.read_text().splitlines()
            if len(lines) > args.file_lines:
                print(f"{path}: {len(lines)} lines (at most {args.file_lines})")
                found += 1
            for line, length, signature in long_functions(lines, args.function_lines):
                print(f"{path}:{line}: {length} lines (at most {args.function_lines}): "
                      f"{signature[:80]}")
                found += 1
    sys.exit(1 if found else 0)


if __name__ == "__main__":
    main()
