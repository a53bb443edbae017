#!/usr/bin/python3
"""Renders shots and lays the results out on a contact sheet PNG.

A starting point for pipeline scripts: copy it and change the loop.

    examples/contact_sheet.py shot1.dof shot2.dof -o sheet.png
    examples/contact_sheet.py --demo -o sheet.png    # an f-stop and focus wedge
                                                     # of the example scene

Each shot's frame (its first, or --frame) is rendered with defocus, kept
as an EXR beside the sheet when --keep is given, turned into display
colour and scaled into a cell of the sheet. Needs the defocus package on
PYTHONPATH (build/python in a build tree) and Debian's python3-openimageio.
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile

import OpenImageIO as oiio
from OpenImageIO import ImageBufAlgo

import defocus


def demo_shots(folder):
    """A wedge over the example scene: three f-stops at two focus distances."""
    scene = os.path.join(folder, "scene.exr")
    maker = os.environ.get("MAKE_EXAMPLE_SCENE_BIN", os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "build", "bin", "make_example_scene"))
    subprocess.run([maker, scene, "--width", "640", "--height", "360"], check=True,
                   stdout=subprocess.DEVNULL)
    shots = []
    for focus in (1.5, 6.0):
        for fstop in (1.4, 2.8, 8.0):
            shot = defocus.Shot(inputs=[scene], focal=50, fstop=fstop, focus=focus,
                                iscolorspace="lin_rec709")
            shots.append((f"f/{fstop:g} at {focus:g} m", shot))
    return shots


def cell(shot, frame, width, keep):
    """A shot's frame, rendered, in display colour, `width` pixels wide."""
    render = defocus.render_imagebuf(shot, frame=frame, crop=True)
    if keep:
        render.write(keep)
    shown = ImageBufAlgo.channels(render, (0, 1, 2))  # premultiplied: over black
    shown = ImageBufAlgo.colorconvert(shown, "linear", "sRGB")
    spec = shown.spec()
    height = max(1, round(spec.height * width / spec.width))
    return ImageBufAlgo.resize(shown, roi=oiio.ROI(0, width, 0, height, 0, 1, 0, 3))


def contact_sheet(cells, labels, columns, gap=8, label_height=24):
    """Cells in rows of `columns`, each with its label under it."""
    width = max(c.spec().width for c in cells)
    height = max(c.spec().height for c in cells) + label_height
    rows = math.ceil(len(cells) / columns)
    sheet = oiio.ImageBuf(oiio.ImageSpec(gap + columns * (width + gap),
                                         gap + rows * (height + gap), 3, oiio.UINT8))
    ImageBufAlgo.fill(sheet, (0.12, 0.12, 0.12))
    for i, (c, label) in enumerate(zip(cells, labels)):
        x = gap + (i % columns) * (width + gap)
        y = gap + (i // columns) * (height + gap)
        ImageBufAlgo.paste(sheet, x, y, 0, 0, c)
        # OpenImageIO 2.4 has no default font on Debian: name one (fonts-dejavu-core).
        # Without it the sheet has no labels.
        ImageBufAlgo.render_text(sheet, x + 4, y + c.spec().height + 18, label, 16,
                                 "DejaVuSans")
    return sheet


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("shots", nargs="*", help=".dof scene files")
    parser.add_argument("--demo", action="store_true",
                        help="render a wedge of the example scene instead")
    parser.add_argument("-o", "--output", required=True, help="the contact sheet (.png)")
    parser.add_argument("--frame", type=int, help="frame to render (default: each shot's first)")
    parser.add_argument("--width", type=int, default=320, help="cell width in pixels")
    parser.add_argument("--columns", type=int, default=3)
    parser.add_argument("--keep", action="store_true",
                        help="also write each render as an EXR beside the sheet")
    args = parser.parse_args()
    if not args.shots and not args.demo:
        parser.error("give .dof files or --demo")

    with tempfile.TemporaryDirectory() as scratch:
        shots = demo_shots(scratch) if args.demo else [
            (os.path.basename(path), defocus.Shot.load(path)) for path in args.shots]
        cells, labels = [], []
        for i, (label, shot) in enumerate(shots):
            keep = None
            if args.keep:
                keep = os.path.splitext(args.output)[0] + f".{i + 1:02d}.exr"
            try:
                cells.append(cell(shot, args.frame, args.width, keep))
            except defocus.Error as error:
                sys.exit(f"contact_sheet: {label}: {error}")
            labels.append(label)
            print(f"rendered {label}", flush=True)
        sheet = contact_sheet(cells, labels, args.columns)
    if not sheet.write(args.output):
        sys.exit(f"contact_sheet: {args.output}: {sheet.geterror()}")
    print(f"wrote {args.output} ({len(cells)} shots)")


if __name__ == "__main__":
    main()
