#!/usr/bin/python3
"""Runs every command the README and the manual show, so that a page that
drifts from the code fails the suite.

    run_examples.py SOURCE_DIR BUILD_DIR [PAGE...]

Each fenced ``sh`` block is run by bash with -e, each ``python`` block by
Python, in the order of its page, in a folder of small example files named
as the pages name them (make_fixtures). A page's blocks share one folder, so
a block may use what an earlier one wrote. A block that must not run here
(it installs packages, builds, or submits to a farm) is preceded by a line
``<!-- not run: REASON -->``. Prints each failure with its page and line and
exits 1 if any block failed.
"""
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

WIDTH, HEIGHT = 320, 180
SEQUENCE = range(1001, 1025)  # render.1001.exr to render.1024.exr
NOT_RUN = re.compile(r"<!--\s*not run:\s*\S.*-->")


def blocks(page):
    """(line, language, text) of each block to run in a Markdown page."""
    found = []
    lines = open(page, encoding="utf-8").read().split("\n")
    i = 0
    while i < len(lines):
        fence = re.match(r"^```(sh|python)\s*$", lines[i])
        if not fence:
            i += 1
            continue
        start = i
        i += 1
        body = []
        while i < len(lines) and not lines[i].startswith("```"):
            body.append(lines[i])
            i += 1
        before = [l for l in lines[:start] if l.strip()]
        if not (before and NOT_RUN.search(before[-1])):
            found.append((start + 1, fence.group(1), "\n".join(body) + "\n"))
        i += 1
    return found


def help_examples(build, tool):
    """The block of examples that `tool --help` ends with, as an 80-column
    terminal shows it (the man page and the manual's commands page show
    the same text)."""
    text = subprocess.run([os.path.join(build, "bin", tool), "--help"], capture_output=True,
                          text=True, check=True, env=dict(os.environ, COLUMNS="80")).stdout
    return [(0, "sh", text.split("\nExamples:\n", 1)[1])]


def run(command, cwd, env):
    result = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True,
                            timeout=600)
    if result.returncode != 0:
        raise RuntimeError(f"{command[0]} failed ({result.returncode}):\n"
                           f"{result.stdout[-2000:]}{result.stderr[-2000:]}")


def write(buf, path):
    if not buf.write(path):
        raise RuntimeError(f"{path}: {buf.geterror()}")


def flat_render(layers_path):
    """The layered scene as a renderer's flat RGBA+Z: its parts composited
    by the pinhole, each pixel's depth that of its front-most opaque part."""
    spec = oiio.ImageBuf(layers_path).spec()
    rgba = np.zeros((spec.full_height, spec.full_width, 4), np.float32)
    z = np.full((spec.full_height, spec.full_width), 1e4, np.float32)
    for part in range(oiio.ImageBuf(layers_path).nsubimages):
        buf = oiio.ImageBuf(layers_path, part, 0)
        roi = oiio.ROI(0, spec.full_width, 0, spec.full_height, 0, 1, 0, 5)
        pixels = buf.get_pixels(oiio.FLOAT, roi)
        alpha = pixels[..., 3:4]
        rgba = pixels[..., :4] + (1 - alpha) * rgba
        z = np.where(pixels[..., 3] > 0.5, pixels[..., 4], z)
    return rgba, z


def image(pixels, channels, attributes=()):
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], len(channels), oiio.FLOAT)
    spec.channelnames = channels
    spec.attribute("colorInteropID", "lin_rec709_scene")
    for name, value in attributes:
        spec.attribute(name, value)
    buf = oiio.ImageBuf(spec)
    buf.set_pixels(oiio.ROI(), pixels.reshape(pixels.shape[0], pixels.shape[1], -1))
    return buf


def without_camera(path):
    """Removes what defocus wrote of its camera, so the file's header does
    not set the f-number of the renders that read it."""
    buf = oiio.ImageBuf(path)
    buf.read(force=True)
    for name in [p.name for p in buf.spec().extra_attribs]:
        if name.startswith("defocus:") or name in ("FNumber", "focus", "aperture"):
            buf.specmod().erase_attribute(name)
    write(buf, path)


def make_fixtures(folder, source, build):
    """The files the pages name, made from the example scene at 320x180."""
    env = dict(os.environ, PATH=f"{build}/bin:" + os.environ["PATH"])
    def tool(*args):
        run(list(args), folder, env)
    tool("make_example_scene", "layers.exr", "--width", str(WIDTH), "--height", str(HEIGHT))
    for name, part in (("bg", 0), ("mid", 1), ("post", 2), ("fg", 3)):
        tool("oiiotool", "layers.exr", "--subimage", str(part), "-o", f"{name}.exr")
    pinhole = ["--fstop", "1000", "--focus", "4", "-q"]
    # A deep render of the set, and the leaves in front of it as a holdout.
    tool("defocus", "bg.exr", "mid.exr", "post.exr", "-o", "deep.exr", "--deep", *pinhole)
    tool("defocus", "fg.exr", "-o", "holdout.exr", "--deep", *pinhole)
    for deep in ("deep.exr", "holdout.exr"):
        without_camera(os.path.join(folder, deep))

    rgba, z = flat_render(os.path.join(folder, "layers.exr"))
    def save(pixels, channels, name, attributes=()):
        write(image(pixels, channels, attributes), os.path.join(folder, name))
    rgbaz = np.dstack([rgba, z])
    save(rgbaz, ["R", "G", "B", "A", "Z"], "flat.exr")
    save(rgbaz, ["R", "G", "B", "A", "Z"], "anamorphic.exr", [("pixelAspectRatio", 2.0)])
    save(np.dstack([rgba, 1 / z]), ["R", "G", "B", "A", "Z"], "nuke.exr")
    ids = np.where(z < 2, 3, np.where(z < 5, 2, 1)).astype(np.float32)
    roughness = np.tile(np.linspace(0, 1, WIDTH, dtype=np.float32), (HEIGHT, 1))
    save(np.dstack([rgbaz, ids, roughness]), ["R", "G", "B", "A", "Z", "matId", "roughness"],
         "flat_aovs.exr")
    save(rgba, ["R", "G", "B", "A"], "plate.exr")
    save(z, ["Z"], "plate_z.exr")
    coc = np.clip(40 * (1 - 4 / z), -40, 40).astype(np.float32)  # 4 m in focus
    save(coc, ["coc"], "coc.exr")
    blender = [f"ViewLayer.Combined.{c}" for c in "RGBA"] + ["ViewLayer.Depth.Z"]
    save(rgbaz, blender, "blender.exr")
    tool("oiiotool", "--colorconfig", os.path.join(source, "ocio", "config.ocio"), "plate.exr",
         "--ch", "R,G,B", "--colorconvert", "lin_rec709", "sRGB",
         "-d", "uint8", "-o", "plate.jpg")

    stereo = [oiio.ImageBuf(os.path.join(folder, "layers.exr"), part, 0) for part in range(4)]
    specs = []
    for view in ("left", "right"):
        for buf in stereo:
            spec = oiio.ImageSpec(buf.spec())
            spec.attribute("view", view)
            part = f"{view}.{buf.spec().getattribute('name')}"
            spec.attribute("name", part)
            spec.attribute("oiio:subimagename", part)
            specs.append(spec)
    out = oiio.ImageOutput.create("stereo.exr")
    if not out.open(os.path.join(folder, "stereo.exr"), specs):
        raise RuntimeError(out.geterror())
    for i, buf in enumerate(stereo * 2):
        if i:
            out.open(os.path.join(folder, "stereo.exr"), specs[i], "AppendSubimage")
        out.write_image(buf.get_pixels(oiio.FLOAT))
    out.close()

    for frame in SEQUENCE:
        os.link(os.path.join(folder, "layers.exr"), os.path.join(folder, f"render.{frame}.exr"))
    for frame in range(1001, 1004):
        os.link(os.path.join(folder, "stereo.exr"), os.path.join(folder, f"stereo.{frame}.exr"))
    os.link(os.path.join(folder, "layers.exr"), os.path.join(folder, "shot.exr"))
    os.link(os.path.join(folder, "plate_z.exr"), os.path.join(folder, "z.exr"))
    for shot in ("a", "b"):
        os.makedirs(os.path.join(folder, "shots", shot))
        tool("defocus", "layers.exr", "--focal", "50", "--fstop", "2", "--focus", "4",
             "--save-scene", f"shots/{shot}/shot.dof")
    # Paths the pages give from the top of a clone.
    os.symlink(build, os.path.join(folder, "build"))
    for name in ("examples", "scripts"):
        os.symlink(os.path.join(source, name), os.path.join(folder, name))


def main():
    source, build = (os.path.abspath(p) for p in sys.argv[1:3])
    pages = sys.argv[3:] or ([os.path.join(source, "README.md")]
                             + sorted(glob.glob(os.path.join(source, "docs", "**", "*.md"),
                                                recursive=True)))
    env = dict(os.environ, PATH=f"{build}/bin:/usr/bin:" + os.environ["PATH"],
               PYTHONPATH=f"{build}/python", OIIO_LIBRARY_PATH=f"{build}/lib",
               COLUMNS="80")
    failures = ran = 0
    with tempfile.TemporaryDirectory() as top:
        fixtures = os.path.join(top, "fixtures")
        os.mkdir(fixtures)
        make_fixtures(fixtures, source, build)
        # defocus-submit's example submits to a farm: tests/farm runs it.
        sources = [(page, blocks(page)) for page in pages]
        if not sys.argv[3:]:
            sources += [(f"{tool} --help", help_examples(build, tool))
                        for tool in ("defocus", "layerize")]
        for page, todo in sources:
            if not todo:
                continue
            name = os.path.relpath(page, source) if page.endswith(".md") else page
            folder = os.path.join(top, name.replace("/", "_").replace(" ", "_"))
            shutil.copytree(fixtures, folder, symlinks=True, copy_function=os.link)
            for line, language, text in todo:
                where = f"{name}:{line}" if line else name
                command = (["bash", "-e", "-o", "pipefail", "-c", text] if language == "sh"
                           else ["/usr/bin/python3", "-c", text])
                ran += 1
                try:
                    run(command, folder, env)
                    print(f"ok   {where}")
                except (RuntimeError, subprocess.TimeoutExpired) as e:
                    failures += 1
                    print(f"FAIL {where}: {e}")
    print(f"{ran - failures} of {ran} documented blocks ran")
    return 1 if failures or not ran else 0


if __name__ == "__main__":
    sys.exit(main())
