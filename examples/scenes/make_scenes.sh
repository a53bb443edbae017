#!/bin/bash
# Renders the test scenes of tests/data/scenes with Blender 3.4 (Debian's
# `blender` package) and lays them out as the shared garden scene is:
#   examples/scenes/make_scenes.sh [OUTDIR]   (default: tests/data/scenes)
# About 40 s a scene on two cores.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-$here/../../tests/data/scenes}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for scene in poles lattice; do
    mkdir -p "$work/$scene"
    blender -b --factory-startup -P "$here/render_layers.py" -- "$scene" "$work/$scene" >"$work/$scene.log" 2>&1 \
        || { cat "$work/$scene.log" >&2; exit 1; }
    /usr/bin/python3 "$here/assemble_scene.py" "$work/$scene" "$out/$scene"
done
