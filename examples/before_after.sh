#!/usr/bin/env bash
# The front page's picture (docs/images/before_after.png): the example
# scene as the pinhole saw it, beside it as the quick start defocuses it
# (examples/run_example.sh: 50 mm f/1.8, focus on the post at 4 m), both
# through the shipped config's sRGB display. Expects a build in build/ and
# oiiotool.
set -euo pipefail
cd "$(dirname "$0")/.."
bash examples/run_example.sh > /dev/null
out=examples/out
build/bin/defocus "$out/scene.exr" -o "$out/pinhole.exr" --preview "$out/pinhole.png" \
    --focal 50 --sensor 36 --focus 4 --fstop 1000 --iscolorspace lin_rec709 -q
oiiotool "$out/pinhole.png" "$out/scene_defocused.png" --mosaic:pad=16 2x1 --resize 1296x360 \
    -o docs/images/before_after.png
echo "wrote docs/images/before_after.png"
