#!/usr/bin/env bash
# Builds the manual into BUILD_DIR/docs/html, warnings as errors:
#   bash docs/build.sh build
# The sources are copied beside the generated pages (the settings reference
# from the settings table, the tools' --help), so the source tree stays as
# committed. Needs python3-sphinx, python3-myst-parser and furo
# (scripts/install-deps.sh), and a build with the Python module for the
# API reference.
set -euo pipefail
if ! /usr/bin/python3 -c "import sphinx, myst_parser, furo" 2>/dev/null; then
    echo "SKIPPED: the manual needs python3-sphinx, python3-myst-parser and furo" \
         "(scripts/install-deps.sh installs them)"
    exit 77
fi
docs="$(cd "$(dirname "$0")" && pwd)"
build="$(cd "${1:?usage: docs/build.sh BUILD_DIR}" && pwd)"
src="$build/docs/src"
rm -rf "$src"
mkdir -p "$src/reference/generated"
cp -r "$docs"/. "$src"
"$build/bin/settings_reference" > "$src/reference/settings.md"
"$build/bin/settings_reference" dof-keys > "$build/docs/dof-keys.md"
marker='<!-- the table of keys: docs/build.sh puts it here -->'
grep -qF "$marker" "$src/reference/dof-format.md" || {
    echo "docs/reference/dof-format.md: the line '$marker' is missing" >&2
    exit 1
}
sed -i -e '/<!-- the table of keys: docs\/build.sh puts it here -->/{r '"$build/docs/dof-keys.md" \
       -e 'd}' "$src/reference/dof-format.md"
for tool in defocus layerize defocus-submit; do
    COLUMNS=100 "$build/bin/$tool" --help > "$src/reference/generated/$tool.txt"
done
PYTHONPATH="$build/python${PYTHONPATH:+:$PYTHONPATH}" \
    /usr/bin/python3 -m sphinx -W --keep-going -q -b html -d "$build/docs/doctrees" "$src" "$build/docs/html"
echo "manual: $build/docs/html/index.html"
