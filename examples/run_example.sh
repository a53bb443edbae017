#!/usr/bin/env bash
# Generates the example layered scene and defocuses it: an EXR and a PNG
# preview in examples/out/. Expects a build in build/ (scripts/build.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin
out=examples/out
mkdir -p "$out"

"$bin/make_example_scene" "$out/scene.exr"
# The scene is 1280 px across a 36 mm filmback; focus on the post at 4 m.
"$bin/defocus" "$out/scene.exr" -o "$out/scene_defocused.exr" \
    --focal 50 --fstop 1.8 --focus 4 --sensor 36 -v
# A display-referred preview of the display window.
oiiotool "$out/scene_defocused.exr" --ch R,G,B --cut 0,0,1279,719 \
    --colorconvert linear sRGB -d uint8 -o "$out/scene_defocused.png"

echo
echo "Layered scene:     $out/scene.exr"
echo "Defocused EXR:     $out/scene_defocused.exr"
echo "Preview (sRGB):    $out/scene_defocused.png"
