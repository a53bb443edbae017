"""The Python module against the defocus command and against itself.

Run by CTest (python_module) with PYTHONPATH at the build tree's package and
DEFOCUS_BIN, MAKE_EXAMPLE_SCENE_BIN and DEFOCUS_SHARED_DATA set.
"""
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import OpenImageIO as oiio
import pytest

import defocus

DEFOCUS_BIN = os.environ["DEFOCUS_BIN"]
GARDEN = os.path.join(os.environ.get("DEFOCUS_SHARED_DATA", ""), "scenes", "garden")


def cli(*args):
    """Runs the defocus command; its stderr when it fails."""
    run = subprocess.run([DEFOCUS_BIN, *map(str, args), "-q"], capture_output=True, text=True)
    return run.returncode, run.stderr.strip()


def pixels(path):
    """A file's pixels in its own pixel type, and its windows."""
    inp = oiio.ImageInput.open(str(path))
    assert inp, oiio.geterror()
    spec = inp.spec()
    data = inp.read_image(oiio.UNKNOWN)
    inp.close()
    return data, (spec.x, spec.y, spec.width, spec.height)


@pytest.fixture(scope="session")
def example(tmp_path_factory):
    """The example scene at 320x180: a four-part layered EXR with overscan."""
    folder = tmp_path_factory.mktemp("example")
    scene = folder / "scene.exr"
    subprocess.run([os.environ["MAKE_EXAMPLE_SCENE_BIN"], str(scene), "--width", "320",
                    "--height", "180"], check=True, capture_output=True)
    return scene


CAMERA = dict(focal=50, fstop=1.8, focus=4.0)
CAMERA_ARGS = ["--focal", "50", "--fstop", "1.8", "--focus", "4"]


def test_render_to_file_is_bit_identical_to_the_command(example, tmp_path):
    assert cli(example, "-o", tmp_path / "cli.exr", *CAMERA_ARGS) == (0, "")
    defocus.render_to_file(defocus.Shot(inputs=[example], **CAMERA), tmp_path / "py.exr")
    ours, theirs = pixels(tmp_path / "py.exr"), pixels(tmp_path / "cli.exr")
    assert ours[1] == theirs[1]
    assert ours[0].dtype == theirs[0].dtype == np.float16
    assert ours[0].tobytes() == theirs[0].tobytes()


def test_render_gives_the_commands_float_pixels(example, tmp_path):
    assert cli(example, "-o", tmp_path / "cli.exr", *CAMERA_ARGS, "-d", "float") == (0, "")
    theirs, window = pixels(tmp_path / "cli.exr")
    ours = defocus.render(defocus.Shot(inputs=[example], **CAMERA))
    assert ours.dtype == np.float32 and ours.shape == (window[3], window[2], 4)
    assert np.array_equal(ours, theirs)
    # The same shot from a .dof file the command saved.
    assert cli(example, *CAMERA_ARGS, "--save-scene", tmp_path / "shot.dof") == (0, "")
    assert np.array_equal(defocus.render(tmp_path / "shot.dof"), theirs)


def test_aperture_cells_composite_per_part_of_the_lens_as_the_command(example, tmp_path):
    assert cli(example, "-o", tmp_path / "cells.exr", *CAMERA_ARGS, "-d", "float",
               "--aperture-cells", "9") == (0, "")
    theirs, _ = pixels(tmp_path / "cells.exr")
    ours = defocus.render(defocus.Shot(inputs=[example], aperture_cells=9, **CAMERA))
    assert np.array_equal(ours, theirs)
    # The leaves in front hide parts of the hills from parts of the lens.
    whole = defocus.render(defocus.Shot(inputs=[example], **CAMERA))
    assert np.abs(ours - whole).max() > 1e-3
    with pytest.raises(defocus.Error, match="aperture_cells"):
        defocus.Shot(aperture_cells=1000)


def test_crop_gives_the_display_window(example):
    shot = defocus.Shot(inputs=[example], **CAMERA)
    whole, cropped = defocus.render(shot), defocus.render(shot, crop=True)
    assert cropped.shape == (180, 320, 4)
    # The example's data window starts 16 pixels before the display window.
    assert np.array_equal(cropped, whole[16:16 + 180, 16:16 + 320])


@pytest.mark.skipif(not os.path.exists(os.path.join(GARDEN, "layers.exr")),
                    reason="no shared data (../shared/data/scenes/garden)")
def test_garden_is_bit_identical_to_the_command(tmp_path):
    layers = os.path.join(GARDEN, "layers.exr")
    assert cli(layers, "-o", tmp_path / "cli.exr", "--focus", "3") == (0, "")
    defocus.render_to_file(defocus.Shot(inputs=[layers], focus=3), tmp_path / "py.exr")
    assert pixels(tmp_path / "py.exr")[0].tobytes() == pixels(tmp_path / "cli.exr")[0].tobytes()


def test_a_focus_pull_sequence_matches_the_commands_frames(example, tmp_path):
    pull = {1: 4.0, 4: 1.5}
    assert cli(example, "--frames", "1-4", "-o", tmp_path / "cli.#.exr", "--focal", "50",
               "--fstop", "1.8", "--focus", "1:4,4:1.5") == (0, "")
    shot = defocus.Shot(inputs=[example], focal=50, fstop=1.8, focus=pull, frames="1-4")
    written = []
    files = defocus.render_sequence(shot, tmp_path / "py.#.exr",
                                    progress=lambda frame, path: written.append(frame))
    assert sorted(written) == [1, 2, 3, 4]
    assert files == [str(tmp_path / f"py.{f:04d}.exr") for f in range(1, 5)]
    frames = [pixels(f)[0] for f in files]
    for f, ours in zip(range(1, 5), frames):
        assert ours.tobytes() == pixels(tmp_path / f"cli.{f:04d}.exr")[0].tobytes()
    # The pull moves the focus: every frame differs from the next.
    assert all(not np.array_equal(a, b) for a, b in zip(frames, frames[1:]))


def test_a_bad_frame_is_reported_after_the_others_are_written(tmp_path, example):
    for f in (1, 2, 4):
        os.symlink(example, tmp_path / f"in.{f:04d}.exr")
    (tmp_path / "in.0003.exr").write_text("not an image")
    shot = defocus.Shot(inputs=[tmp_path / "in.#.exr"], frames="1-4", **CAMERA)
    with pytest.raises(defocus.Error, match=r"^3 of 4 frames written; failed: 3; frame 3: .*"
                                            r"in\.0003\.exr: "):
        defocus.render_sequence(shot, tmp_path / "out.#.exr")
    assert sorted(os.listdir(tmp_path)) == sorted(
        [f"in.{f:04d}.exr" for f in range(1, 5)] + [f"out.{f:04d}.exr" for f in (1, 2, 4)])


def test_a_missing_frame_is_refused_before_any_is_rendered(tmp_path, example):
    for f in (1, 2, 4):
        os.symlink(example, tmp_path / f"in.{f:04d}.exr")
    shot = defocus.Shot(inputs=[tmp_path / "in.#.exr"], **CAMERA)
    with pytest.raises(defocus.Error, match=r"in\.0003\.exr: no such file; frames with input "
                                            r"files missing: 3"):
        defocus.render_sequence(shot, tmp_path / "out.#.exr")
    assert not [f for f in os.listdir(tmp_path) if f.startswith("out")]
    shot.missing_frames = "hold"
    defocus.render_sequence(shot, tmp_path / "out.#.exr")
    assert pixels(tmp_path / "out.0003.exr")[0].tobytes() == \
        pixels(tmp_path / "out.0002.exr")[0].tobytes()


def layered_arrays(width=96, height=64):
    """Three layers of a small scene: a far gradient, a mid disc, a near bar."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float32)
    far = np.zeros((height, width, 4), np.float32)
    far[..., 0], far[..., 1], far[..., 2], far[..., 3] = x / width, y / height, 0.3, 1.0
    mid = np.zeros_like(far)
    inside = (x - 40) ** 2 + (y - 30) ** 2 < 15 ** 2
    mid[inside] = (4.0, 2.0, 0.5, 1.0)
    near = np.zeros_like(far)
    near[:, 70:78] = (0.1, 0.2, 0.8, 0.75)
    depth = lambda z: np.full((height, width), z, np.float32)
    return [(far, depth(20.0), "far"), (mid, depth(3.0), "mid"), (near, depth(0.8), "near")]


def write_layers(layers, path, origin=(0, 0), display=None):
    """A multi-part EXR, one float RGBA+Z part per layer, its data window at
    `origin` in the display window `display` (x, y, width, height; default
    the data window)."""
    specs = []
    for rgba, z, name in layers:
        spec = oiio.ImageSpec(rgba.shape[1], rgba.shape[0], 5, oiio.FLOAT)
        spec.x, spec.y = origin
        if display:
            spec.full_x, spec.full_y, spec.full_width, spec.full_height = display
        spec.channelnames = ("R", "G", "B", "A", "Z")
        spec.alpha_channel, spec.z_channel = 3, 4
        spec.attribute("name", name)
        specs.append(spec)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), specs)
    for i, (rgba, z, _) in enumerate(layers):
        if i > 0:
            assert out.open(str(path), specs[i], "AppendSubimage")
        assert out.write_image(np.concatenate([rgba, z[..., None]], axis=2))
    out.close()


SMALL_CAMERA = dict(focal=50, fstop=1.4, focus=3.0, sensor=5)


def test_arrays_in_give_the_pixels_of_the_same_layers_from_a_file(tmp_path):
    layers = layered_arrays()
    write_layers(layers, tmp_path / "layers.exr")
    from_file = defocus.render(defocus.Shot(inputs=[tmp_path / "layers.exr"], **SMALL_CAMERA))
    from_arrays = defocus.render_layers(layers, **SMALL_CAMERA)
    assert from_arrays.shape == from_file.shape
    assert np.array_equal(from_arrays, from_file)
    # The blur did something: the near bar's edges are soft.
    assert 0.0 < from_arrays[32, 66, 3] < 1.0 or from_arrays[32, 66, 2] != layers[0][0][32, 66, 2]
    # Settings through a shot and a camera dict give the same.
    shot = defocus.Shot(focal=50, fstop=1.4)
    assert np.array_equal(
        defocus.render_layers(layers, shot, camera=dict(focus=3.0, sensor=5)), from_file)


def test_imagebufs_in_and_out(tmp_path):
    layers = layered_arrays()
    bufs = []
    for rgba, z, name in layers:
        color = oiio.ImageBuf(oiio.ImageSpec(rgba.shape[1], rgba.shape[0], 4, oiio.FLOAT))
        color.set_pixels(color.roi, rgba)
        depth = oiio.ImageBuf(oiio.ImageSpec(z.shape[1], z.shape[0], 1, oiio.FLOAT))
        depth.set_pixels(depth.roi, z[..., None])  # OIIO 2.4 misreads 2-D arrays
        bufs.append((color, depth, name))
    assert np.array_equal(defocus.render_layers(bufs, **SMALL_CAMERA),
                          defocus.render_layers(layers, **SMALL_CAMERA))
    write_layers(layers, tmp_path / "layers.exr")
    shot = defocus.Shot(inputs=[tmp_path / "layers.exr"], **SMALL_CAMERA)
    buf = defocus.render_imagebuf(shot)
    assert isinstance(buf, oiio.ImageBuf)
    assert np.array_equal(buf.get_pixels(oiio.FLOAT), defocus.render(shot))
    assert buf.spec().get_float_attribute("defocus:focusDistance") == pytest.approx(3.0)
    assert buf.spec().get_string_attribute("defocus:aperture") == "disc"
    assert (buf.roi_full.width, buf.roi_full.height) == (96, 64)


def test_decompose_cuts_a_flat_render_into_layers_that_composite_back():
    height, width = 64, 96
    rgba = np.zeros((height, width, 4), np.float32)
    rgba[...] = (0.2, 0.4, 0.6, 1.0)
    z = np.full((height, width), 30.0, np.float32)
    rgba[20:40, 30:60] = (3.0, 1.0, 0.5, 1.0)
    z[20:40, 30:60] = 1.0
    layers = defocus.decompose(rgba, z, **SMALL_CAMERA)
    assert len(layers) >= 2
    # The camera as a dict in the shot's place gives the same layers.
    again = defocus.decompose(rgba, z, SMALL_CAMERA)
    assert all(np.array_equal(a[0], b[0]) for a, b in zip(layers, again))
    near_depths = [np.median(lz[la[..., 3] > 0]) for la, lz, _ in layers]
    assert near_depths == sorted(near_depths, reverse=True)  # back to front
    over = np.zeros_like(rgba)
    for layer_rgba, _, _ in layers:
        over = layer_rgba + (1.0 - layer_rgba[..., 3:4]) * over
    assert np.allclose(over, rgba, rtol=1e-6, atol=1e-6)
    # render_layers takes them as they are; the in-focus square stays sharp.
    out = defocus.render_layers(layers, **{**SMALL_CAMERA, "focus": 1.0})
    assert np.allclose(out[30, 45], rgba[30, 45], rtol=1e-4)


def striped_wall_behind_a_bar(height=64, width=96):
    """A flat render: a near bar in front of a striped wall."""
    rgba = np.ones((height, width, 4), np.float32)
    rgba[(np.arange(height) // 4) % 2 == 0, :, :3] = 0.1
    z = np.full((height, width), 20.0, np.float32)
    rgba[:, 40:50] = (0.5, 0.5, 0.5, 1.0)
    z[:, 40:50] = 0.8
    return rgba, z


def test_one_layer_is_a_flat_render_cut_into_layers_as_the_command_does(tmp_path):
    rgba, z = striped_wall_behind_a_bar()
    write_layers([(rgba, z, "flat")], tmp_path / "flat.exr")
    camera = {**SMALL_CAMERA, "focus": 20.0}
    from_file = defocus.render(defocus.Shot(inputs=[tmp_path / "flat.exr"], **camera))
    assert np.array_equal(defocus.render_layers([(rgba, z)], **camera), from_file)
    # The layers decompose() gives render as they are to nearly the same
    # (they no longer say which of their pixels were rebuilt).
    layers = defocus.decompose(rgba, z, **camera)
    assert len(layers) >= 2
    assert np.allclose(defocus.render_layers(layers, **camera), from_file, atol=0.01)


def test_overscan_is_passed_as_origin_and_display_window(tmp_path):
    # 96x64 arrays: a display window of 80x48 with 8 px of overscan around.
    layers = layered_arrays()
    origin, display = (-8, -8), (0, 0, 80, 48)
    write_layers(layers, tmp_path / "overscan.exr", origin, display)
    from_file = defocus.render(defocus.Shot(inputs=[tmp_path / "overscan.exr"], **SMALL_CAMERA))
    ours = defocus.render_layers(layers, origin=origin, display_window=display, **SMALL_CAMERA)
    assert np.array_equal(ours, from_file)
    cropped = defocus.render_layers(layers, origin=origin, display_window=display, crop=True,
                                    **SMALL_CAMERA)
    assert cropped.shape == (48, 80, 4) and np.array_equal(cropped, from_file[8:56, 8:88])
    # Without them the arrays are the display window: a wider frame, so
    # the same lens blurs less in pixels.
    assert not np.array_equal(defocus.render_layers(layers, **SMALL_CAMERA), from_file)
    # ImageBufs bring their own windows.
    bufs = []
    for rgba, z, name in layers:
        spec = oiio.ImageSpec(rgba.shape[1], rgba.shape[0], 4, oiio.FLOAT)
        spec.x, spec.y = origin
        spec.full_x, spec.full_y, spec.full_width, spec.full_height = display
        color = oiio.ImageBuf(spec)
        color.set_pixels(color.roi, rgba)
        spec.nchannels, spec.channelnames = 1, ("Z",)
        depth = oiio.ImageBuf(spec)
        depth.set_pixels(depth.roi, z[..., None])
        bufs.append((color, depth, name))
    assert np.array_equal(defocus.render_layers(bufs, **SMALL_CAMERA), from_file)
    with pytest.raises(ValueError, match=r"differ from the ImageBufs'"):
        defocus.render_layers(bufs, origin=(0, 0), **SMALL_CAMERA)
    with pytest.raises(ValueError, match=r"display_window: expected \(x, y, width, height\)"):
        defocus.render_layers(layers, display_window=(0, 0, 80), **SMALL_CAMERA)
    with pytest.raises(ValueError, match=r"display_window: \(0, 0, 0, 48\) is empty"):
        defocus.render_layers(layers, display_window=(0, 0, 0, 48), **SMALL_CAMERA)
    # (rgba, z, z): the third item is the layer's name.
    rgba, z, _ = layers[0]
    with pytest.raises(TypeError, match=r"layers\[0\]: the third item is the layer's name, a "
                                        r"str, not a ndarray"):
        defocus.render_layers([(rgba, z, z)], **SMALL_CAMERA)


def test_unset_settings_read_none_and_resolved_gives_what_a_render_uses(tmp_path):
    # A render whose header records its lens: f/5.6 at 85 mm.
    spec = oiio.ImageSpec(96, 64, 5, oiio.FLOAT)
    spec.channelnames = ("R", "G", "B", "A", "Z")
    spec.alpha_channel, spec.z_channel = 3, 4
    spec.attribute("FNumber", 5.6)
    spec.attribute("CameraFocalLength", 85.0)
    rgba, z = striped_wall_behind_a_bar()
    out = oiio.ImageOutput.create(str(tmp_path / "lens.exr"))
    assert out.open(str(tmp_path / "lens.exr"), spec)
    assert out.write_image(np.concatenate([rgba, z[..., None]], axis=2))
    out.close()
    shot = defocus.Shot(inputs=[tmp_path / "lens.exr"], focus={1: 2.0, 11: 8.0}, sensor=5)
    assert shot.fstop is None and shot.focal is None and shot.aperture is None
    assert shot.sensor == 5 and shot.focus == {1: 2.0, 11: 8.0}
    used = defocus.render_imagebuf(shot, frame=6).spec()
    resolved = shot.resolved(6)
    assert resolved["fstop"] == pytest.approx(5.6) == used.get_float_attribute("defocus:fNumber")
    assert resolved["focal"] == pytest.approx(85.0)
    assert resolved["focus"] == pytest.approx(used.get_float_attribute("defocus:focusDistance"))
    assert 2.0 < resolved["focus"] < 8.0  # the keyframes taken at frame 6
    assert resolved["aperture"] == "disc" and resolved["blades"] == 6
    assert resolved["camera_from_file"] is True and shot.camera_from_file is None
    # Given values win over the header, as in a render.
    shot.fstop = 2.0
    assert shot.fstop == 2.0 and shot.resolved(6)["fstop"] == 2.0
    # Focusing at a pixel measures the depth there.
    shot.focus_at = (20, 10)
    assert shot.focus is None and shot.resolved()["focus"] == pytest.approx(20.0)
    shot.camera_from_file = False
    assert shot.camera_from_file is False  # a bool, not the text "off", which is true
    assert shot.resolved()["fstop"] == 2.0 and shot.resolved()["focal"] == 50.0
    # A .dof file may say it in JSON's own words.
    (tmp_path / "shot.dof").write_text(
        f'{{"version": 1, "inputs": ["lens.exr"], "camera": {{"focus": 3, "from_file": false}}}}')
    assert defocus.Shot.load(tmp_path / "shot.dof").resolved()["fstop"] == 2.8


def test_polygon_settings_are_refused_alike_everywhere(example, tmp_path):
    shot = defocus.Shot(inputs=[example], blades=5, **CAMERA)
    with pytest.raises(defocus.Error, match=r'^blades applies only to aperture="polygon" '
                                            r'\(the aperture is disc\)$'):
        shot.check()
    with pytest.raises(defocus.Error, match=r"blades applies only"):
        defocus.render(shot)
    shot.aperture = "polygon"
    shot.check()
    code, message = cli(example, "-o", tmp_path / "out.exr", *CAMERA_ARGS, "--roundness", "0.5")
    assert code != 0 and message.endswith("--roundness applies only to --aperture polygon "
                                          "(the aperture is disc)")
    (tmp_path / "shot.dof").write_text(
        f'{{"version": 1, "inputs": ["{example}"], "camera": {{"focus": 4}}, '
        f'"aperture": {{"rotation": 10}}}}')
    code, message = cli(tmp_path / "shot.dof", "-o", tmp_path / "out.exr")
    assert code != 0 and "aperture.rotation applies only to" in message
    with pytest.raises(defocus.Error, match=r"aperture.rotation applies only to"):
        defocus.Shot.load(tmp_path / "shot.dof").check()


def test_errors_name_python_keywords(example, tmp_path):
    cases = [
        (defocus.Shot(inputs=[example], camera_from_file=False),
         "focus=DIST or focus_at=X,Y is required: where the focus is"),
        (defocus.Shot(inputs=[example], focus=3, output="focusmap", aov="confidence"),
         'aov applies to the defocused image, not to output="focusmap"'),
        (defocus.Shot(inputs=[example], focus_at=(5000, 10)),
         "focus_at=(5000, 10) is outside the 320x180 display window"),
        (defocus.Shot(inputs=[example], focus=3, memory_limit="1M"),
         "more than the memory limit of 1 MB (memory_limit)"),
        (defocus.Shot(inputs=[example], focus=3, depth_kind="coc"),
         'focus has no meaning for a depth that is a CoC map (depth_kind="coc")'),
    ]
    for shot, words in cases:
        with pytest.raises(defocus.Error) as raised:
            defocus.render(shot)
        assert words in str(raised.value)
        assert "--" not in str(raised.value)
    with pytest.raises(defocus.Error, match=r"^focus_at: expected a pixel \(x, y\), got 'a'$"):
        defocus.Shot(focus_at="a")
    with pytest.raises(defocus.Error, match=r"^depth_kind: unknown depth kind 'far' \(choose z, "):
        defocus.Shot(depth_kind="far")
    with pytest.raises(defocus.Error, match=r"^bloom: 0 is out of range"):
        defocus.Shot(bloom=(0, 4))
    # Arguments of the wrong type name the keyword and what it takes, never
    # pybind's NativeShot and arg0.
    shot = defocus.Shot(inputs=[example], focus=3)
    for call in (lambda: defocus.render(shot, frame="x"),
                 lambda: defocus.render_imagebuf(shot, frame=1.5),
                 lambda: defocus.focus_map(shot, frame=True),
                 lambda: defocus.render_to_file(shot, tmp_path / "x.exr", frame="2"),
                 lambda: shot.resolved("x"),
                 lambda: shot.settings_hash(None),
                 lambda: defocus.frame_path("a.#.exr", "1")):
        with pytest.raises(TypeError, match=r"^frame: expected a whole frame number") as raised:
            call()
        assert "NativeShot" not in str(raised.value) and "arg0" not in str(raised.value)
    with pytest.raises(TypeError, match=r"^crop: expected True or False, got 'yes'$"):
        defocus.render(shot, crop="yes")


def test_the_confidence_aov_marks_rebuilt_light_as_the_command_does(example, tmp_path):
    # Layered input hides nothing: the channel is there, and 0.
    layered = defocus.render(defocus.Shot(inputs=[example], aov="confidence", **CAMERA))
    assert layered.shape[2] == 9 and not layered[..., 4:].any()
    # A flat render: a near bar, blurred, hides part of a striped wall.
    height, width = 64, 96
    rgba, z = striped_wall_behind_a_bar(height, width)
    write_layers([(rgba, z, "flat")], tmp_path / "flat.exr")
    camera = {**SMALL_CAMERA, "focus": 20.0}
    ours = defocus.render(defocus.Shot(inputs=[tmp_path / "flat.exr"], aov="confidence",
                                       **camera))
    assert ours.shape == (height, width, 9)
    confidence = ours[..., 4]
    assert confidence[32, 45] > 0.1 and confidence.max() <= 1.0
    assert not confidence[:, :20].any()  # beyond the bar's blur all was seen
    # Then that share by method (continued, lines, patterns, smooth): their sum.
    assert np.allclose(ours[..., 5:].sum(axis=2), confidence, atol=1e-5)
    args = [f"--{k}={v}" for k, v in camera.items()]
    assert cli(tmp_path / "flat.exr", "-o", tmp_path / "cli.exr", "--aov", "confidence",
               "-d", "float", *args) == (0, "")
    theirs, _ = pixels(tmp_path / "cli.exr")
    assert np.array_equal(ours, theirs)


def test_a_holdout_and_the_coc_aov_as_the_command_and_a_dof_give_them(example, tmp_path):
    # A flat card at 2 m over the left half of the example's display window:
    # the holdout, one sample a pixel.
    spec = oiio.ImageSpec(320, 180, 5, oiio.FLOAT)
    spec.channelnames = ("R", "G", "B", "A", "Z")
    card = np.zeros((180, 320, 5), np.float32)
    card[:, :160] = (0.2, 0.2, 0.2, 1.0, 2.0)
    out = oiio.ImageOutput.create(str(tmp_path / "card.exr"))
    assert out.open(str(tmp_path / "card.exr"), spec)
    out.write_image(card)
    out.close()
    shot = defocus.Shot(inputs=[example], holdout=tmp_path / "card.exr", aov="coc", **CAMERA)
    ours = defocus.render(shot)
    plain = defocus.render(defocus.Shot(inputs=[example], **CAMERA))
    assert ours.shape[2] == 5
    # Cut behind the card (all but the leaves at 1 m, in front of it), and
    # only there; the CoC channel is the wall's and the leaves'.
    assert not np.array_equal(ours[..., :4], plain)
    beyond_card = 16 + 160 + 16  # overscan, the card's half, more than its blur
    assert np.array_equal(ours[:, beyond_card:, :4], plain[:, beyond_card:])
    assert ours[..., 4].min() < 0 < ours[..., 4].max()
    assert cli(example, "-o", tmp_path / "cli.exr", "--holdout", tmp_path / "card.exr",
               "--aov", "coc", "-d", "float", *CAMERA_ARGS) == (0, "")
    theirs, _ = pixels(tmp_path / "cli.exr")
    assert np.array_equal(ours, theirs)
    shot.save(tmp_path / "shot.dof")
    assert np.array_equal(defocus.render(tmp_path / "shot.dof"), theirs)


def test_a_deep_result_is_written_as_the_command_and_a_dof_write_it(example, tmp_path):
    shot = defocus.Shot(inputs=[example], deep=True, pixel_type="float", **CAMERA)
    with pytest.raises(defocus.Error, match="deep=True makes a deep image"):
        defocus.render(shot)
    defocus.render_to_file(shot, tmp_path / "py.exr")
    assert cli(example, "-o", tmp_path / "cli.exr", "--deep", "-d", "float",
               *CAMERA_ARGS) == (0, "")
    shot.save(tmp_path / "shot.dof")
    defocus.render_to_file(tmp_path / "shot.dof", tmp_path / "dof.exr")
    ours = oiio.ImageBuf(str(tmp_path / "py.exr"))
    assert ours.deep and ours.spec().channelnames == ("R", "G", "B", "A", "Z", "ZBack")
    for other in ("cli.exr", "dof.exr"):
        theirs = oiio.ImageBuf(str(tmp_path / other))
        assert oiio.ImageBufAlgo.compare(ours, theirs, 0, 0).maxerror == 0
    # Flattened, it is the flat result.
    flat = defocus.render(defocus.Shot(inputs=[example], pixel_type="float", **CAMERA))
    flattened = oiio.ImageBufAlgo.flatten(ours).get_pixels(oiio.FLOAT)[..., :4]
    assert np.abs(flattened - flat).max() < 1e-5


def test_data_channels_as_the_command_and_a_dof_carry_them(tmp_path):
    # A card at 1 m (ID 7) in front of a wall at 6 m (ID 3), with P.
    spec = oiio.ImageSpec(96, 64, 9, oiio.FLOAT)
    spec.channelnames = ("R", "G", "B", "A", "Z", "objectId", "P.x", "P.y", "P.z")
    scene = np.zeros((64, 96, 9), np.float32)
    scene[:] = (0.2, 0.3, 0.4, 1.0, 6.0, 3.0, 0.0, 0.0, 6.0)
    scene[20:44, 30:60] = (0.9, 0.8, 0.1, 1.0, 1.0, 7.0, 0.0, 0.0, 1.0)
    out = oiio.ImageOutput.create(str(tmp_path / "flat.exr"))
    assert out.open(str(tmp_path / "flat.exr"), spec)
    out.write_image(scene)
    out.close()
    shot = defocus.Shot(inputs=[tmp_path / "flat.exr"], data_channels="auto", **SMALL_CAMERA)
    ours = defocus.render(shot)
    assert ours.shape[2] == 4 + 2 + 4  # RGBA, Z and ZFront, the ID and P
    assert set(np.unique(ours[..., 6])) <= {3.0, 7.0}  # never a mix
    assert set(np.unique(np.round(ours[..., 9], 4))) <= {1.0, 6.0}
    assert ours[..., 4].min() >= 1.0 - 1e-4 and ours[..., 4].max() <= 6.0 + 1e-4
    defocus.render_to_file(shot, tmp_path / "py.exr")
    shot.save(tmp_path / "shot.dof")
    defocus.render_to_file(tmp_path / "shot.dof", tmp_path / "dof.exr")
    args = [word for k, v in SMALL_CAMERA.items() for word in (f"--{k}", str(v))]
    assert cli(tmp_path / "flat.exr", "-o", tmp_path / "cli.exr", "--data-channels", "auto",
               *args) == (0, "")
    theirs, _ = pixels(tmp_path / "cli.exr")
    for other in ("py.exr", "dof.exr"):
        assert np.array_equal(pixels(tmp_path / other)[0], theirs)
    assert np.array_equal(ours, theirs)
    with pytest.raises(defocus.Error, match=r'data_channels="auto,uv": the input has no channel uv'):
        defocus.render(defocus.Shot(inputs=[tmp_path / "flat.exr"], data_channels="auto,uv",
                                    **SMALL_CAMERA))


@pytest.mark.parametrize("bad, message", [
    (lambda l: [(l[0][0].astype(np.float64), l[0][1])], r"rgba: dtype float64; expected float32"),
    (lambda l: [(l[0][0][..., :3], l[0][1])], r"rgba: shape \(64, 96, 3\); expected"),
    (lambda l: [(l[0][0], l[0][1][:10])], r"z is 96x10, rgba 96x64"),
    (lambda l: [(l[0][0], l[0][1]), (l[1][0][:32], l[1][1][:32])], r"96x32, the first layer 96x64"),
    (lambda l: [(l[0][0], l[0][1].astype(np.int32))], r"z: dtype int32"),
    (lambda l: [("not an image", l[0][1])], r"expected a numpy array or an OpenImageIO"),
    (lambda l: [], r"no layers"),
])
def test_bad_arrays_raise_value_errors(bad, message):
    with pytest.raises(ValueError, match=message):
        defocus.render_layers(bad(layered_arrays()), **SMALL_CAMERA)


def test_errors_carry_the_commands_messages(tmp_path):
    code, message = cli(tmp_path / "missing.exr", "-o", tmp_path / "out.exr", "--focus", "3")
    assert code != 0
    with pytest.raises(defocus.Error) as raised:
        defocus.render(defocus.Shot(inputs=[tmp_path / "missing.exr"], focus=3))
    assert "defocus: " + str(raised.value) == message
    assert isinstance(raised.value, RuntimeError)
    with pytest.raises(defocus.Error, match=r"unknown setting 'fsop'"):
        defocus.Shot(fsop=2)
    with pytest.raises(defocus.Error, match=r"fstop: -1 is out of range"):
        defocus.Shot(fstop=-1)
    with pytest.raises(defocus.Error, match=r"focus: keyframe 1.5 is not a whole frame"):
        defocus.Shot(focus={1.5: 3.0})
    with pytest.raises(AttributeError):
        defocus.Shot().fsop
    (tmp_path / "bad.dof").write_text('{"version": 1, "inputs": ["a.exr"], "camera": {"fsop": 2}}')
    code, message = cli(tmp_path / "bad.dof", "-o", tmp_path / "out.exr")
    with pytest.raises(defocus.Error) as raised:
        defocus.Shot.load(tmp_path / "bad.dof")
    assert "defocus: " + str(raised.value) == message


def test_shots_round_trip_through_dof_files(tmp_path):
    shot = defocus.Shot(inputs=[tmp_path / "plate.#.exr"], frames=range(1001, 1041), focal=85, fstop=1.4,
                        focus={1001: 3.0, 1040: 1.2}, focus_tilt=(5, 0), aperture="polygon",
                        blades=7, max_blur=200, depth_kind="distance", bloom=(0.9, 4))
    assert shot.focus == {1001: 3.0, 1040: 1.2}
    assert shot.frames == "1001-1040" and shot.blades == 7 and shot.aperture == "polygon"
    assert shot.depth_kind == "distance" and shot.bloom == (0.9, 4)
    assert shot.focus_at is None
    shot.save(tmp_path / "shot.dof")
    loaded = defocus.Shot.load(tmp_path / "shot.dof")
    assert loaded == shot
    assert loaded.inputs == [str(tmp_path / "plate.#.exr")]
    assert repr(loaded).startswith("Shot(inputs=[") and "focus={1001: 3.0, 1040: 1.2}" in repr(loaded)
    # Setting focus_at clears focus, as on the command line.
    loaded.focus_at = {1001: (640, 360), 1040: (200, 300)}
    assert loaded.focus is None and loaded.focus_at[1040] == (200.0, 300.0)


def test_two_threads_render_at_once_with_identical_results(example):
    shot = defocus.Shot(inputs=[example], **CAMERA)
    alone = defocus.render(shot)
    results = [None, None]

    def run(i):
        results[i] = defocus.render(shot)
    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert np.array_equal(results[0], alone) and np.array_equal(results[1], alone)


def test_ctrl_c_raises_keyboard_interrupt_and_leaves_no_partial_file(example, tmp_path):
    script = textwrap.dedent(f"""
        import sys, defocus
        shot = defocus.Shot(inputs=[{str(example)!r}], frames="1-100", focal=50, fstop=1.8,
                            focus={{1: 4.0, 100: 1.5}})
        def progress(frame, path):
            print("written", path, flush=True)
        try:
            defocus.render_sequence(shot, {str(tmp_path / "out.#.exr")!r}, progress=progress)
        except KeyboardInterrupt:
            print("interrupted", flush=True)
            sys.exit(3)
    """)
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True,
                             env=os.environ)
    assert child.stdout.readline().startswith("written")
    child.send_signal(signal.SIGINT)
    start = time.monotonic()
    out, _ = child.communicate(timeout=60)
    assert child.returncode == 3 and "interrupted" in out
    assert time.monotonic() - start < 10
    files = os.listdir(tmp_path)
    assert 0 < len(files) < 100
    for name in files:
        assert name.startswith("out.") and name.endswith(".exr"), name  # no temporaries
        assert pixels(tmp_path / name)[0].shape == (212, 352, 4)


def test_help_reads_well():
    assert "render_layers" in defocus.__doc__
    for name in defocus.__all__:
        obj = getattr(defocus, name)
        if callable(obj):
            assert obj.__doc__ and len(obj.__doc__) > 40, name
    for name in ("load", "save", "frames_to_render", "given"):
        assert getattr(defocus.Shot, name).__doc__, name
    assert defocus.__version__ == subprocess.run(
        [DEFOCUS_BIN, "--version"], capture_output=True, text=True).stdout.split()[-1]
    assert defocus.settings()["aperture"] == "aperture.shape"


def test_the_contact_sheet_example_runs(tmp_path):
    script = os.path.join(os.environ["EXAMPLES_DIR"], "contact_sheet.py")
    run = subprocess.run([sys.executable, script, "--demo", "-o", str(tmp_path / "sheet.png"),
                          "--width", "160", "--keep"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    sheet = oiio.ImageBuf(str(tmp_path / "sheet.png"))
    assert (sheet.spec().width, sheet.spec().height) == (8 + 3 * 168, 8 + 2 * (90 + 24 + 8))
    assert len([f for f in os.listdir(tmp_path) if f.endswith(".exr")]) == 6
    # Six different renders: the wedge's cells differ.
    cells = [sheet.get_pixels(oiio.FLOAT, oiio.ROI(8 + c * 168, 8 + c * 168 + 160,
                                                   8 + r * 122, 8 + r * 122 + 90))
             for r in range(2) for c in range(3)]
    assert all(not np.array_equal(a, b) for i, a in enumerate(cells) for b in cells[i + 1:])


def test_chunks_and_skip_existing_on_the_command_line(example, tmp_path):
    pull = ["--focal", "50", "--fstop", "1.8", "--focus", "1:4,6:1.5", "--frames", "1-6"]
    out = tmp_path / "f.#.exr"
    for k in (1, 2, 3):
        assert cli(example, *pull, "-o", out, "--chunk", f"{k}/3") == (0, "")
    frames = [tmp_path / f"f.{f:04d}.exr" for f in range(1, 7)]
    mtimes = [f.stat().st_mtime_ns for f in frames]
    # The Python module records the same settings hash as the command.
    shot = defocus.Shot(inputs=[example], focal=50, fstop=1.8, focus={1: 4.0, 6: 1.5},
                        frames="1-6")
    for f, path in zip(range(1, 7), frames):
        assert defocus.written_with_settings(path, shot.settings_hash(f)) == (True, "")
    run = subprocess.run([DEFOCUS_BIN, str(example), *pull, "-o", str(out), "--skip-existing"],
                         capture_output=True, text=True)
    assert run.returncode == 0 and "0 of 0 frames written (6 more skipped" in run.stdout
    assert [f.stat().st_mtime_ns for f in frames] == mtimes
    # Other settings: every frame is rendered again, and -v says why.
    frames[2].unlink()
    other = [a if a != "1.8" else "2.8" for a in pull]
    run = subprocess.run([DEFOCUS_BIN, str(example), *other, "-o", str(out),
                          "--skip-existing", "--chunk", "2/3", "-v"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "frame 4: rendering again" in run.stdout and "other settings" in run.stdout
    assert "2 of 2 frames written" in run.stdout
    assert frames[3].stat().st_mtime_ns != mtimes[3]


def test_defocus_submit_dry_run_prints_the_batch_scripts(example, tmp_path):
    submit = os.path.join(os.path.dirname(DEFOCUS_BIN), "defocus-submit")
    run = subprocess.run([submit, "--dry-run", "--chunk-size", "10", "--cpus", "2", "--mem", "3G",
                          "--job-dir", str(tmp_path / "job"), str(example), "--frames", "1-24",
                          "--focus", "1:4,24:1.5", "-o", str(tmp_path / "f.#.exr")],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    for line in ["#SBATCH --array=1,2,3", "#SBATCH --cpus-per-task=2", "#SBATCH --mem=3072M",
                 f"#SBATCH --output={tmp_path}/job/chunk_%a.log", '--chunk "$SLURM_ARRAY_TASK_ID/3"',
                 "--skip-existing", "#SBATCH --dependency=afterany:<array job id>", "--check"]:
        assert line in run.stdout, line
    assert not (tmp_path / "job").exists()  # a dry run writes nothing
    run = subprocess.run([submit, "--chunk-size", "10", str(example), "--focus", "4",
                          "-o", str(tmp_path / "nowhere" / "f.#.exr")], capture_output=True,
                         text=True)
    assert run.returncode != 0 and "does not exist" in run.stderr
    run = subprocess.run([submit, "--chunk-size", "10", str(tmp_path / "in.#.exr"), "--frames",
                          "1-24", "--focus", "4", "-o", str(tmp_path / "f.#.exr")],
                         capture_output=True, text=True)
    assert run.returncode != 0
    assert run.stderr.startswith(f"defocus-submit: {tmp_path}/in.0001.exr: no such file; "
                                 "frames with input files missing: 1-24")
