#!/usr/bin/python3
"""Turns render_layers.py's Blender renders into a scene as the garden scene
of ../shared/data is laid out:
  layers.exr  a part a layer (back to front), R, G, B, A half and Z float
  flat.exr    the whole scene at once, the same channels
  deep.exr    the layers merged into one deep image (oiiotool --deepen
              --deepmerge, which drops samples behind an opaque one), each
              partly covered pixel at its surface's depth
  truth_focus<F>.exr  the thin lens, R, G, B, A over the display window
The inputs carry the overscan margin the renders have around the display
window.
  assemble_scene.py RENDERS OUTDIR
  assemble_scene.py --deep OUTDIR    deep.exr again, from OUTDIR/layers.exr"""
import glob
import os
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio

LAYERS = ("far", "lights", "mid", "near")
WIDTH, HEIGHT, OVERSCAN = 480, 270, 48


def rgbaz(path, name=None, truth=False):
    """Blender's multilayer EXR as R, G, B, A (and Z) with the windows set."""
    image = oiio.ImageBuf(path)
    names = ["ViewLayer.Combined." + c for c in "RGBA"] + ([] if truth else ["ViewLayer.Depth.Z"])
    out = oiio.ImageBufAlgo.channels(image, tuple(names),
                                     tuple(["R", "G", "B", "A"] + ([] if truth else ["Z"])))
    spec = out.specmod()
    margin = 0 if truth else OVERSCAN
    spec.x = spec.y = -margin
    spec.full_x = spec.full_y = 0
    spec.full_width, spec.full_height = WIDTH, HEIGHT
    spec.alpha_channel = 3
    if name:
        spec.attribute("name", name)
    return out


def write(image, path, half=True):
    spec = oiio.ImageSpec(image.spec())
    spec.attribute("compression", "zip")
    spec.set_format(oiio.HALF if half else oiio.FLOAT)
    if image.spec().nchannels == 5:
        spec.channelformats = (oiio.HALF,) * 4 + (oiio.FLOAT,)
    out = oiio.ImageOutput.create(path)
    out.open(path, spec)
    out.write_image(image.get_pixels(oiio.FLOAT))
    out.close()


EMPTY = 1e9  # Blender's depth where a pixel's first sample hit nothing is 1e10


def surface_depths(part, reach=3):
    """`part` with each partly covered pixel at the depth of its surface.
    Blender writes a pixel's depth from one sample, so a pixel its surface
    covers in part has the empty depth when that sample missed it; a
    renderer's deep output holds the surface's sample there, at the
    surface's depth. It takes the nearest depth within `reach` pixels."""
    pixels = part.get_pixels(oiio.FLOAT)
    alpha, depth = pixels[..., 3], pixels[..., 4]
    missing = (alpha > 0) & (depth >= EMPTY)
    best = np.full(depth.shape, np.inf)
    nearest = np.full(depth.shape, np.inf)
    height, width = depth.shape
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            shifted = np.full(depth.shape, EMPTY * 10, dtype=depth.dtype)
            shifted[max(dy, 0):height + min(dy, 0), max(dx, 0):width + min(dx, 0)] = \
                depth[max(-dy, 0):height + min(-dy, 0), max(-dx, 0):width + min(-dx, 0)]
            distance = dx * dx + dy * dy
            closer = (shifted < EMPTY) & (distance < nearest)
            nearest[closer], best[closer] = distance, shifted[closer]
    fixed = missing & np.isfinite(best)
    depth[fixed] = best[fixed]
    out = oiio.ImageBuf(part.spec())
    out.set_pixels(oiio.ROI(), pixels)
    return out


def write_deep(parts, outdir):
    single = []
    for k, part in enumerate(parts):
        single.append(f"{outdir}/.part{k}.exr")
        write(surface_depths(part), single[-1])
    command = ["oiiotool"]
    for k, path in enumerate(single):
        command += [path, "--deepen"] + (["--deepmerge"] if k > 0 else [])
    subprocess.run(command + ["-d", "half", "-d", "Z=float", "--compression", "zips",
                              "--scanline", "-o", f"{outdir}/deep.exr"],
                   check=True)
    for path in single:
        os.remove(path)


def main():
    if sys.argv[1] == "--deep":
        outdir = sys.argv[2]
        layers = f"{outdir}/layers.exr"
        write_deep([oiio.ImageBuf(layers, k, 0) for k in range(len(LAYERS))], outdir)
        return
    renders, outdir = sys.argv[1:3]
    os.makedirs(outdir, exist_ok=True)
    parts = [rgbaz(f"{renders}/layer_{name}.exr", name) for name in LAYERS]
    specs = []
    for part in parts:
        spec = oiio.ImageSpec(part.spec())
        spec.attribute("compression", "zip")
        spec.channelformats = (oiio.HALF,) * 4 + (oiio.FLOAT,)
        specs.append(spec)
    out = oiio.ImageOutput.create(f"{outdir}/layers.exr")
    out.open(f"{outdir}/layers.exr", specs)
    for k, part in enumerate(parts):
        if k > 0:
            out.open(f"{outdir}/layers.exr", specs[k], "AppendSubimage")
        out.write_image(part.get_pixels(oiio.FLOAT))
    out.close()
    write(rgbaz(f"{renders}/flat.exr"), f"{outdir}/flat.exr")
    write_deep(parts, outdir)
    for path in sorted(glob.glob(f"{renders}/truth_focus*.exr")):
        write(rgbaz(path, truth=True), f"{outdir}/{os.path.basename(path)}")


if __name__ == "__main__":
    main()
