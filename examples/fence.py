#!/usr/bin/python3
"""The fence test as pictures: a far light behind near bars, defocused with
sub-aperture compositing, by the thin lens itself, and over the whole
aperture at once (the layered model).

    examples/fence.py DEFOCUS_BIN OUT.png [WORK_DIR]

The scene (as the suite's fence test): a light 20 times brighter than the
wall around it at 10 m, behind bars 4 px wide every 16 px at 1 m; 85 mm f/1.4
focused at 3 m over a 600 px wide frame. The thin lens: each layer, planar,
shifted by its CoC radius times each point of a 64 x 64 grid over the
aperture (those in the disc), composited with "over", averaged.
"""
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

SIZE, FULL_W, FULL_H = 96, 600, 400
X0, Y0 = 252, 152                     # data window in the display window
K = 0.085 ** 2 / (1.4 * 0.036) * FULL_W  # CoC diameter per unit of 1/z, px


def radius(z):
    return 0.5 * K * (1.0 / 3.0 - 1.0 / z)


def layers():
    ys, xs = np.mgrid[0:SIZE, 0:SIZE] + 0.5
    light = np.full((SIZE, SIZE, 4), 0.05, np.float32)
    light[..., 3] = 1.0
    light[np.hypot(xs - 48, ys - 48) < 3.0, :3] = 1.0
    bars = np.zeros((SIZE, SIZE, 4), np.float32)
    column = (np.arange(SIZE) - 48 + 8) % 16
    on = (column >= 6) & (column < 10)
    bars[:, on] = (0.01, 0.01, 0.01, 1.0)
    return [(light, 10.0, "light"), (bars, 1.0, "bars")]


def write_scene(path):
    specs, pixels = [], []
    for rgba, z, name in layers():
        spec = oiio.ImageSpec(SIZE, SIZE, 5, oiio.FLOAT)
        spec.x, spec.y = X0, Y0
        spec.full_x = spec.full_y = 0
        spec.full_width, spec.full_height = FULL_W, FULL_H
        spec.channelnames = ("R", "G", "B", "A", "Z")
        spec.alpha_channel, spec.z_channel = 3, 4
        spec.attribute("name", name)
        specs.append(spec)
        pixels.append(np.dstack([rgba, np.full((SIZE, SIZE, 1), z, np.float32)]))
    out = oiio.ImageOutput.create(path)
    if not out.open(path, specs):
        raise SystemExit(out.geterror())
    for i, (spec, data) in enumerate(zip(specs, pixels)):
        if i:
            out.open(path, spec, "AppendSubimage")
        out.write_image(data)
    out.close()


def shift(image, dx, dy):
    """The image moved by (dx, dy) px, split bilinearly; zero comes in."""
    ix, iy = int(np.floor(dx)), int(np.floor(dy))
    fx, fy = dx - ix, dy - iy
    out = np.zeros_like(image)
    for ox, oy, w in ((0, 0, (1 - fx) * (1 - fy)), (1, 0, fx * (1 - fy)),
                      (0, 1, (1 - fx) * fy), (1, 1, fx * fy)):
        sx, sy = ix + ox, iy + oy
        src = image[max(0, -sy):SIZE - max(0, sy), max(0, -sx):SIZE - max(0, sx)]
        out[max(0, sy):max(0, sy) + src.shape[0], max(0, sx):max(0, sx) + src.shape[1]] += w * src
    return out


def thin_lens(samples=64):
    total, count = np.zeros((SIZE, SIZE, 4)), 0
    u = -1.0 + (np.arange(samples) + 0.5) * 2.0 / samples
    for uy in u:
        for ux in u:
            if ux * ux + uy * uy > 1.0:
                continue
            composite = np.zeros((SIZE, SIZE, 4))
            for rgba, z, _ in layers():
                r = radius(z)
                seen = shift(rgba.astype(np.float64), r * ux, r * uy)
                composite = seen + (1.0 - seen[..., 3:4]) * composite
            total += composite
            count += 1
    return total / count


def window(image):
    """The light's bokeh, enlarged, brightened five times, as sRGB."""
    crop = np.clip(image[36:60, 36:60, :3] * 5.0, 0.0, 1.0)
    crop = np.where(crop <= 0.0031308, 12.92 * crop, 1.055 * crop ** (1 / 2.4) - 0.055)
    return np.kron(crop, np.ones((8, 8, 1)))


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    defocus, out = sys.argv[1], sys.argv[2]
    work = sys.argv[3] if len(sys.argv) > 3 else tempfile.mkdtemp()
    scene = os.path.join(work, "fence.exr")
    write_scene(scene)
    renders = []
    for cells in ("0", "1"):
        path = os.path.join(work, f"fence_cells{cells}.exr")
        subprocess.run([defocus, scene, "-o", path, "--focal", "85", "--fstop", "1.4",
                        "--focus", "3", "--aperture-cells", cells, "-d", "float", "-q"],
                       check=True)
        renders.append(oiio.ImageBuf(path).get_pixels(oiio.FLOAT)[..., :4])
    gap = np.ones((24 * 8, 8, 3))
    sheet = np.hstack([window(renders[0]), gap, window(thin_lens()), gap, window(renders[1])])
    buf = oiio.ImageBuf(oiio.ImageSpec(sheet.shape[1], sheet.shape[0], 3, oiio.UINT8))
    buf.set_pixels(oiio.ROI(), (sheet * 255 + 0.5).astype(np.uint8))
    if not buf.write(out):
        raise SystemExit(buf.geterror())
    print(f"wrote {out}: cells, the thin lens, one cell")


if __name__ == "__main__":
    main()
