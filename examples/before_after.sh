#!/usr/bin/env bash
# The front page's picture (docs/images/before_after.png): the example
# scene as the pinhole saw it, beside it defocused as the quick start
# defocuses it (50 mm f/1.8, focus on the post at 4 m), both through the
# shipped config's sRGB display. Expects a build in build/ and oiiotool.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin
out=examples/out
mkdir -p "$out"
"$bin/make_example_scene" "$out/scene.exr"
camera=(--focal 50 --sensor 36 --focus 4 --iscolorspace lin_rec709 -q)
"$bin/defocus" "$out/scene.exr" -o "$out/before.exr" --preview "$out/before.png" \
    --fstop 1000 "${camera[@]}"
"$bin/defocus" "$out/scene.exr" -o "$out/after.exr" --preview "$out/after.png" \
    --fstop 1.8 "${camera[@]}"
oiiotool "$out/before.png" "$out/after.png" --mosaic:pad=16 2x1 --resize 1296x360 -o docs/images/before_after.png
echo "wrote docs/images/before_after.png"
