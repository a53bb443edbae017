#!/bin/bash
# The hidden-background fill on the poles scene as pictures: the wall
# behind two poles as a flat render's slicing rebuilds it, and the flat
# render defocused, by two builds side by side with the truth.
#   examples/scenes/fill_picture.sh BEFORE_BIN_DIR AFTER_BIN_DIR OUT.png
# (each BIN_DIR holds defocus and layerize)
set -euo pipefail
before=$1 after=$2 out=$3
scene=$(cd "$(dirname "$0")/../../tests/data/scenes/poles" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
camera="--focal 85 --fstop 2 --focus 3"
crop="--cut 160x120+200+20 --resize 320x240"
for build in before after; do
    bin=${!build}
    "$bin/layerize" "$scene/flat.exr" -o "$work/$build.layers.exr" $camera
    "$bin/defocus" "$scene/flat.exr" -o "$work/$build.exr" $camera --aperture disc -q
    oiiotool "$work/$build.layers.exr" --subimage 0 --ch R,G,B --colorconvert linear sRGB $crop \
        -o "$work/$build.wall.png"
    oiiotool "$work/$build.exr" --ch R,G,B --colorconvert linear sRGB $crop -o "$work/$build.out.png"
done
oiiotool "$scene/layers.exr" --subimage 0 --ch R,G,B --colorconvert linear sRGB $crop \
    -o "$work/truth.wall.png"
oiiotool "$scene/truth_focus3.exr" --ch R,G,B --colorconvert linear sRGB $crop \
    -o "$work/truth.out.png"
oiiotool "$work/before.wall.png" "$work/after.wall.png" "$work/truth.wall.png" \
    "$work/before.out.png" "$work/after.out.png" "$work/truth.out.png" \
    --mosaic:pad=4 3x2 -o "$out"
