#!/usr/bin/env bash
# A field of point lights far behind the focus, defocused with the lens
# effects that change over the frame: optical vignetting (cat's eye) and
# lateral chromatic aberration. Writes examples/out/point_field*.exr and a
# PNG of each. Expects a build in build/ (scripts/build.sh) and oiiotool.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin
out=examples/out
mkdir -p "$out"

# 960x540, opaque black at 1 km, a light of 200 every 60 pixels.
lights=()
for y in $(seq 30 60 539); do
    for x in $(seq 30 60 959); do
        lights+=(--box:color=200,200,200:fill=1 "$x,$y,$x,$y")
    done
done
oiiotool --create 960x540 3 "${lights[@]}" --ch R,G,B,A=1.0,Z=1000.0 -o "$out/point_field.exr"

# A 50 mm f/1.4 focused at 1 m: the lights blur to about 48 px.
camera=(--focal 50 --fstop 1.4 --focus 1 --iscolorspace lin_rec709)
"$bin/defocus" "$out/point_field.exr" -o "$out/point_field_cateye.exr" "${camera[@]}" \
    --cateye 1 --preview "$out/point_field_cateye.png"
"$bin/defocus" "$out/point_field.exr" -o "$out/point_field_lateral_ca.exr" "${camera[@]}" \
    --lateral-ca 0.01 --preview "$out/point_field_lateral_ca.png"
