#!/usr/bin/python3
"""What no flat or deep render can know: writes a layered EXR (one part per
layer: R, G, B, A, Z) with every light that the pinhole view does not see at
all put out, its pixels given the mean colour of the layer around it (the
best guess a fill of a flat render can make there).

    scripts/unseen_lights.py LAYERS.exr OUT.exr [RATIO]

A light is a connected patch of a layer's pixels RATIO times (default 3)
brighter than the layer's mean within 15 px, grown by a pixel for its rim;
it is unseen where the nearer layers leave less than 5% of every one of its
pixels uncovered. Rendered beside LAYERS.exr, OUT.exr tells how much of a
region's error no rebuild of hidden content can remove (issue 63's
garden bar: see the notes). Debian's /usr/bin/python3 with numpy and
OpenImageIO's module."""
import sys

import numpy as np
import OpenImageIO as oiio


def read_parts(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        sys.exit(f"{path}: {oiio.geterror()}")
    specs, pixels = [], []
    while inp.seek_subimage(len(specs), 0):
        spec = oiio.ImageSpec(inp.spec())
        specs.append(spec)
        pixels.append(inp.read_image(len(pixels), 0, 0, spec.nchannels, oiio.FLOAT))
    inp.close()
    return specs, pixels


def channel(spec, name):
    return list(spec.channelnames).index(name)


def uncovered(specs, pixels):
    """Per layer and pixel, how much the nearer layers leave uncovered."""
    depth = np.stack([np.where(p[..., channel(s, "A")] > 0, p[..., channel(s, "Z")], np.inf)
                      for s, p in zip(specs, pixels)])
    alpha = np.stack([np.clip(p[..., channel(s, "A")], 0, 1) for s, p in zip(specs, pixels)])
    order = np.argsort(depth, axis=0)
    front_to_back = np.take_along_axis(alpha, order, 0)
    through = np.cumprod(np.concatenate([np.ones_like(front_to_back[:1]), 1 - front_to_back[:-1]]),
                         axis=0)
    out = np.empty_like(through)
    np.put_along_axis(out, order, through, 0)
    return out


def box_mean(values, weights, radius):
    """Weighted mean over a (2 radius + 1)^2 box, by summed-area tables."""
    def box_sum(a):
        s = np.pad(a, (radius + 1, radius)).cumsum(0).cumsum(1)
        n = 2 * radius + 1
        return s[n:, n:] - s[:-n, n:] - s[n:, :-n] + s[:-n, :-n]
    return box_sum(values * weights) / np.maximum(box_sum(weights), 1e-9)


def grow(mask):
    grown = mask.copy()
    grown[1:] |= mask[:-1]
    grown[:-1] |= mask[1:]
    grown[:, 1:] |= mask[:, :-1]
    grown[:, :-1] |= mask[:, 1:]
    return grown


def patches(mask):
    """The 4-connected patches of `mask`, each as (rows, columns)."""
    todo = set(zip(*np.nonzero(mask)))
    while todo:
        stack, patch = [todo.pop()], []
        while stack:
            y, x = stack.pop()
            patch.append((y, x))
            for n in ((y - 1, x), (y + 1, x), (y, x - 1), (y, x + 1)):
                if n in todo:
                    todo.remove(n)
                    stack.append(n)
        yield tuple(np.array(patch).T)


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    src, dst = sys.argv[1], sys.argv[2]
    ratio = float(sys.argv[3]) if len(sys.argv) == 4 else 3.0
    specs, pixels = read_parts(src)
    through = uncovered(specs, pixels)
    out = oiio.ImageOutput.create(dst)
    if out is None or not out.open(dst, specs):
        sys.exit(f"{dst}: {oiio.geterror()}")
    for k, (spec, p) in enumerate(zip(specs, pixels)):
        if k > 0:
            out.open(dst, spec, "AppendSubimage")
        rgb = [channel(spec, c) for c in "RGB"]
        present = p[..., channel(spec, "A")] > 0.5
        level = p[..., rgb] @ np.array([0.2126, 0.7152, 0.0722])
        around = box_mean(level, present.astype(float), 15)
        bright = present & (level > ratio * np.maximum(around, 1e-4))
        unmixed = present & ~bright
        result, count, area = p.copy(), 0, 0
        for patch in patches(grow(bright) & (p[..., channel(spec, "A")] > 0)):
            if (through[k][patch] > 0.05).any():
                continue
            ring = np.zeros_like(present)
            ring[patch] = True
            for _ in range(4):
                ring = grow(ring)
            ring[patch] = False
            ring &= unmixed
            for c in rgb:
                result[..., c][patch] = p[..., c][ring].mean() if ring.any() else 0.0
            count, area = count + 1, area + len(patch[0])
        print(f"{spec.getattribute('name') or k}: {count} unseen lights, {area} px")
        out.write_image(result)
    out.close()


main()
