#!/usr/bin/env bash
# Generates the example layered scene and defocuses it: an EXR, a PNG
# preview and the .dof scene file of the settings in examples/out/. Expects
# a build in build/ (scripts/build.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin
out=examples/out
mkdir -p "$out"

"$bin/make_example_scene" "$out/scene.exr"
# The scene is 1280 px across a 36 mm filmback, in linear Rec.709; focus
# on the post at 4 m. The preview goes through the shipped config's sRGB
# display, ACES 1.0 SDR video view.
"$bin/defocus" "$out/scene.exr" -o "$out/scene_defocused.exr" \
    --focal 50 --fstop 1.8 --focus 4 --sensor 36 --iscolorspace lin_rec709 \
    --preview "$out/scene_defocused.png" --save-scene "$out/scene.dof" -v

echo
echo "Layered scene:     $out/scene.exr"
echo "Defocused EXR:     $out/scene_defocused.exr"
echo "Preview (sRGB display): $out/scene_defocused.png"
echo "Scene file:        $out/scene.dof"
echo "  render it again:      $bin/defocus $out/scene.dof -o out.exr --fstop 4"
echo "  or in any OIIO tool:  OIIO_LIBRARY_PATH=build/lib oiiotool $out/scene.dof -o out.exr"
