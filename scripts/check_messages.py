#!/usr/bin/env python3
"""Checks that no string literal in the library's C++ names a command-line
flag: the library names a setting with mention() and each front end words
it (see lib/include/defocus/shot/setting_words.h).

    scripts/check_messages.py LIB_FOLDER

The settings table (lib/src/shot/settings_table.cpp) is the one place that
holds the command line's spelling of each setting and its help. Prints each
literal that names a flag and exits 1 if there is any."""
import pathlib
import re
import sys

LITERAL = re.compile(r'"(?:[^"\\\n]|\\.)*"')
FLAG = re.compile(r"(?:^|[\s(,'])--?[a-z][a-z0-9-]*\b")
TABLE = "settings_table.cpp"


def code_of(line):
    """`line` without its // comment."""
    in_string = False
    for i, c in enumerate(line):
        if c == '"' and (i == 0 or line[i - 1] != "\\"):
            in_string = not in_string
        elif not in_string and line.startswith("//", i):
            return line[:i]
    return line


def main():
    found = 0
    for path in sorted(pathlib.Path(sys.argv[1]).rglob("*")):
        if path.suffix not in (".cpp", ".h") or path.name == TABLE:
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            for literal in LITERAL.findall(code_of(line)):
                if FLAG.search(literal[1:-1]):
                    print(f"{path}:{number}: a message names a flag: {literal}")
                    found += 1
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
