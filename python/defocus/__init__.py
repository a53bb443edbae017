"""Depth of field for layered scenes, from Python.

defocus spreads each layer of a scene over its circle of confusion and
composites the spread layers back to front (Kosloff, Tao & Barsky,
"Depth of Field Postprocessing for Layered Scenes Using Constant-Time
Rectangle Spreading", Graphics Interface 2009). This package renders with
the same library as the ``defocus`` command, so the same shot gives the
same pixels.

A shot holds the inputs and the settings, named as the command's options
with ``_`` for ``-`` (``fstop``, ``focus_at``, ``max_blur``)::

    import defocus
    shot = defocus.Shot(inputs=["layers.exr"], focal=85, fstop=1.4, focus=3.0)
    shot.focus = {1001: 3.0, 1040: 1.2}          # keyframes
    pixels = defocus.render(shot, frame=1001)    # float32, height x width x 4
    defocus.render_to_file(shot, "dof.exr", frame=1001)
    defocus.render_sequence(shot, "dof.#.exr", frames=range(1001, 1041))
    shot.save("shot.dof")                       # defocus shot.dof -o ... renders it

An unset setting reads None (``shot.fstop``); ``shot.resolved(frame)``
gives what a render of that frame uses, the input's header included.

Layers you already hold render from memory: ``render_layers([(rgba, z),
...], focus=3.0)`` with premultiplied RGBA and depth as float32 arrays, or
OpenImageIO ImageBufs (``import OpenImageIO``; ``render_imagebuf`` gives an
ImageBuf back with the result's windows and metadata). One (rgba, z) is a
flat render and is cut into layers, as the command cuts it; pass
``origin=(x, y)`` and ``display_window=(x, y, w, h)`` for overscan.

Failures raise ``defocus.Error`` (a RuntimeError) with the command's
one-line message, settings named as keywords (``focus=`` for the command's
``--focus``); bad arrays raise ValueError. Renders release the GIL, so
threads render side by side, and Ctrl-C stops a render at its next stage
with KeyboardInterrupt, leaving no partial file.
"""

import os
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _defocus
from ._defocus import Error

__all__ = [
    "Error",
    "Shot",
    "settings",
    "render",
    "render_imagebuf",
    "render_to_file",
    "render_sequence",
    "focus_map",
    "render_layers",
    "decompose",
    "frame_path",
    "chunk_frames",
    "written_with_settings",
    "__version__",
]

__version__: str = _defocus.__version__

Error.__doc__ = """A shot, a file or a frame failed, with the defocus command's one-line
message (the file and the problem). A subclass of RuntimeError."""

# How each setting's value is written (ShotValueKind in shot.h).
_NUMBER, _KEYFRAMES, _POINT, _TEXT, _PATH, _FILE_OR_NAME, _SWITCH = range(7)
_SETTINGS = {name.replace("-", "_"): (name, section, key, kind)
             for name, section, key, kind in _defocus.settings()}


def settings() -> Dict[str, str]:
    """Every setting a Shot takes, with where a .dof file keeps it.

    Returns {python_name: "section.key"}, e.g. {"fstop": "camera.fstop",
    "aperture": "aperture.shape", ...}. The names are the defocus command's
    options without the dashes, with "_" for "-".
    """
    return {name: f"{section}.{key}" for name, (_, section, key, _k) in _SETTINGS.items()}


def _number_text(value: Any, name: str) -> str:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise Error(f"{name}: expected a number, got {value!r}")
    return repr(int(value)) if isinstance(value, (int, np.integer)) else repr(float(value))


def _point_text(value: Any, name: str) -> str:
    try:
        x, y = value
    except (TypeError, ValueError):
        raise Error(f"{name}: expected a pixel (x, y), got {value!r}") from None
    return f"{_number_text(x, name)},{_number_text(y, name)}"


def _keyed_text(value: Any, name: str, one: Callable[[Any, str], str]) -> str:
    if isinstance(value, dict):
        if not value:
            raise Error(f"{name}: no keyframes")
        keys = []
        for frame in sorted(value):
            if isinstance(frame, bool) or not isinstance(frame, (int, np.integer)):
                raise Error(f"{name}: keyframe {frame!r} is not a whole frame number")
            keys.append(f"{int(frame)}:{one(value[frame], name)}")
        return ",".join(keys)
    return one(value, name)


def _frames_text(value: Any) -> str:
    if isinstance(value, range):
        if len(value) == 0:
            raise Error("frames: an empty range")
        last = value[-1]
        step = value.step
        if step < 0:
            raise Error("frames: a range must count up")
        return f"{value.start}-{last}" + (f"x{step}" if step != 1 else "")
    if isinstance(value, (list, tuple)):
        return ",".join(str(int(f)) for f in value)
    return str(value)


def _to_text(name: str, value: Any) -> str:
    """A Python value as the text the command line gives the setting."""
    kind = _SETTINGS[name][3]
    if value is None:
        return ""
    if kind == _NUMBER:
        return _number_text(value, name)
    if kind == _KEYFRAMES:
        return _keyed_text(value, name, _number_text)
    if kind == _POINT:
        return _keyed_text(value, name, _point_text)
    if name == "frames":
        return _frames_text(value)
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if not isinstance(value, str):
        raise Error(f"{name}: expected text, got {value!r}")
    return value


def _number(text: str) -> Union[int, float]:
    try:
        return int(text)
    except ValueError:
        return float(text)


def _from_text(python_name: str, text: str) -> Any:
    """The setting's text as a Python value (None when unset)."""
    _, _, _, kind = _SETTINGS[python_name]
    if text == "":
        return None
    if kind == _NUMBER:
        return _number(text)
    if kind == _SWITCH:
        return text == "on"
    if kind in (_KEYFRAMES, _POINT):
        arity = 1 if kind == _KEYFRAMES else 2
        parts = text.split(",")
        if ":" not in text:
            values = tuple(float(p) for p in parts)
            return values[0] if arity == 1 else values
        keys = {}
        for i in range(0, len(parts), arity):
            frame, first = parts[i].split(":")
            values = (float(first),) + tuple(float(p) for p in parts[i + 1:i + arity])
            keys[int(frame)] = values[0] if arity == 1 else values
        return keys
    return text


class Shot:
    """Everything that says how to render a scene, frame by frame.

    ``Shot(inputs=[...], focal=85, fstop=1.4, focus=3.0, aperture="disc")``
    takes the defocus command's options as keywords (``-`` written ``_``;
    ``defocus.settings()`` lists them). A keyframed setting (focus, focal,
    fstop, focus_at, ...) takes a number, or a dict {frame: value}; a pixel
    setting (focus_at, optical_centre) takes (x, y). Settings read and
    write as attributes; an unset one reads None, and ``resolved(frame)``
    gives the values a render of that frame uses (defaults, the input's
    header, keyframes taken at the frame). ``Shot.load`` reads a .dof scene
    file and ``save`` writes one.
    """

    __slots__ = ("_native",)

    def __init__(self, inputs: Optional[Sequence[Union[str, os.PathLike]]] = None,
                 **settings: Any) -> None:
        object.__setattr__(self, "_native", _defocus.NativeShot())
        if inputs is not None:
            self.inputs = inputs
        for name, value in settings.items():
            self._set(name, value)

    @classmethod
    def load(cls, path: Union[str, os.PathLike]) -> "Shot":
        """Reads a .dof scene file; its relative paths are taken from its folder."""
        shot = cls()
        object.__setattr__(shot, "_native", _defocus.load_shot(os.fspath(path)))
        return shot

    def save(self, path: Union[str, os.PathLike]) -> None:
        """Writes the shot as a .dof scene file, atomically (paths beneath
        its folder are written relative to it)."""
        self._native.save(os.fspath(path))

    def to_json(self, directory: Union[str, os.PathLike] = "") -> str:
        """The .dof text of the shot, paths relative to `directory`."""
        return self._native.to_json(os.fspath(directory))

    def copy(self) -> "Shot":
        """An independent copy."""
        shot = Shot()
        object.__setattr__(shot, "_native", _defocus.NativeShot(self._native))
        return shot

    def frames_to_render(self) -> List[int]:
        """The frames the shot renders: its frame list, else the frames its
        input patterns find on disk, else [1] for a still."""
        return self._native.frames()

    def settings_hash(self, frame: int) -> str:
        """The fingerprint of what `frame` is rendered with (inputs, every
        setting, the frame), which each output records as
        defocus:settingsHash: ``defocus --skip-existing`` skips a frame
        whose output has the same."""
        return self._native.settings_hash(_frame(frame, optional=False))

    def resolved(self, frame: Optional[int] = None) -> Dict[str, Any]:
        """Every setting as a render of `frame` (default: the shot's first)
        uses it: {name: value}. Unset settings take their defaults; with
        camera_from_file, the camera values the input's header records
        (focal, fstop, focus, sensor) take the place of unset ones; the
        keyframed camera values are taken at the frame, and with focus_at
        the focus is the depth measured there. Reads the input's header
        (its pixels too with focus_at); raises Error as render() does."""
        values = {name: _from_text(name, self._native.get(native))
                  for name, (native, *_r) in _SETTINGS.items()}
        values.update(self._native.resolved_camera(_frame(frame)))
        return values

    def check(self) -> None:
        """Raises Error with the first reason the shot cannot be rendered."""
        self._native.check()

    def given(self) -> Dict[str, Any]:
        """The settings that were set, as {name: value}."""
        return {name: getattr(self, name) for name, (native, *_r) in _SETTINGS.items()
                if self._native.is_given(native)}

    @property
    def inputs(self) -> List[str]:
        """The files or frame patterns (``shot.#.exr``) of one scene's layers."""
        return list(self._native.inputs)

    @inputs.setter
    def inputs(self, files: Sequence[Union[str, os.PathLike]]) -> None:
        if isinstance(files, (str, os.PathLike)):
            files = [files]
        self._native.inputs = [os.fspath(f) for f in files]

    def _set(self, name: str, value: Any) -> None:
        if name not in _SETTINGS:
            raise Error(f"unknown setting '{name}' (defocus.settings() lists them)")
        self._native.set(_SETTINGS[name][0], _to_text(name, value), name)

    def __getattr__(self, name: str) -> Any:
        if name not in _SETTINGS:
            raise AttributeError(f"Shot has no setting '{name}' (defocus.settings() lists them)")
        native = _SETTINGS[name][0]
        if not self._native.is_given(native):
            return None
        return _from_text(name, self._native.get(native))

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "inputs":
            object.__setattr__(self, name, value)
        else:
            self._set(name, value)

    def __dir__(self) -> Iterable[str]:
        return list(super().__dir__()) + list(_SETTINGS)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Shot) and self.to_json() == other.to_json()

    def __repr__(self) -> str:
        args = [f"inputs={self.inputs!r}"] + [f"{k}={v!r}" for k, v in self.given().items()]
        return f"Shot({', '.join(args)})"


_ShotArg = Union[Shot, str, os.PathLike]


def _shot(shot: _ShotArg) -> Shot:
    return shot if isinstance(shot, Shot) else Shot.load(shot)


def _frame(frame: Any, optional: bool = True) -> Optional[int]:
    """A frame argument checked here, so that a wrong one names the
    keyword, not pybind's arguments."""
    if frame is None and optional:
        return None
    if isinstance(frame, (int, np.integer)) and not isinstance(frame, bool):
        return int(frame)
    takes = "a whole frame number (int)" + (" or None" if optional else "")
    raise TypeError(f"frame: expected {takes}, got {frame!r}")


def _flag(value: Any, name: str) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise TypeError(f"{name}: expected True or False, got {value!r}")


def _image_spec(xml: str):
    import OpenImageIO as oiio
    spec = oiio.ImageSpec()
    spec.from_xml(xml)
    return spec


def _imagebuf(pixels: np.ndarray, xml: str):
    import OpenImageIO as oiio
    spec = _image_spec(xml)
    spec.set_format(oiio.FLOAT)
    buf = oiio.ImageBuf(spec)
    buf.set_pixels(buf.roi, pixels)
    return buf


def render(shot: _ShotArg, frame: Optional[int] = None, crop: bool = False) -> np.ndarray:
    """Renders a frame of a shot (a Shot or a .dof file) as defocus does.

    Returns float32 pixels, height x width x 4 (premultiplied R,G,B,A in the
    output colour space; with aov="confidence", five more channels: the
    share of each pixel's light from rebuilt hidden surfaces, then that
    share by how they were rebuilt, continued behind edges, along lines,
    as copied patterns and by the smooth fill; with aov="coc", a fifth: the
    signed CoC in pixels of the front-most layer reaching it) over the
    result's data window, or with crop=True
    over the display window (black outside the data). frame=None renders
    the shot's first frame. The pixels are those defocus writes, before
    conversion to the output's pixel type (e.g. half).
    """
    return _defocus.render(_shot(shot)._native, _frame(frame), _flag(crop, "crop"))[0]


def render_imagebuf(shot: _ShotArg, frame: Optional[int] = None, crop: bool = False):
    """render() as an OpenImageIO.ImageBuf (float), with the result's data
    and display windows and metadata (camera, settings, colour space)."""
    return _imagebuf(*_defocus.render(_shot(shot)._native, _frame(frame), _flag(crop, "crop")))


def focus_map(shot: _ShotArg, frame: Optional[int] = None, crop: bool = False) -> np.ndarray:
    """Where the focus falls in a frame, in false colour (defocus --output
    focusmap): float32, height x width x 4, over the display window."""
    return _defocus.focus_map(_shot(shot)._native, _frame(frame), _flag(crop, "crop"))[0]


def render_to_file(shot: _ShotArg, path: Union[str, os.PathLike],
                   frame: Optional[int] = None) -> None:
    """Renders a frame and writes it atomically, exactly as ``defocus -o
    path`` does (format from the extension, the shot's pixel type and
    compression, metadata kept). Never overwrites an input."""
    _defocus.render_to_file(_shot(shot)._native, os.fspath(path), _frame(frame))


def render_sequence(shot: _ShotArg, output: Union[str, os.PathLike],
                    frames: Optional[Iterable[int]] = None,
                    progress: Optional[Callable[[int, str], None]] = None,
                    threads: int = 0, stop_on_error: bool = False) -> List[str]:
    """Renders frames to a frame pattern (``dof.#.exr``), side by side as the
    cores and the memory limit allow, as ``defocus`` does.

    frames: the frames to render (default: the shot's). progress(frame,
    path) is called as each frame is written, from a worker thread.
    threads: worker threads (0 = all cores). A bad frame does not stop the
    others (unless stop_on_error): once they are written, Error says
    "N of M frames written; failed: ..." with each failed frame's reason.
    Returns the files written, in frame order.
    """
    frame_list = None if frames is None else [int(f) for f in frames]
    return _defocus.render_sequence(_shot(shot)._native, os.fspath(output), frame_list,
                                    progress, threads, stop_on_error)


def frame_path(pattern: Union[str, os.PathLike], frame: int) -> str:
    """The file of `frame` in a frame pattern (``dof.#.exr`` -> ``dof.1001.exr``),
    as defocus names it; `pattern` itself when it is not one."""
    return _defocus.frame_path(os.fspath(pattern), _frame(frame, optional=False))


def chunk_frames(frames: Sequence[int], k: int, n: int) -> List[int]:
    """The K-th (1-based) of `n` chunks of `frames`, as ``defocus --chunk K/N``
    renders it: neighbouring frames, sizes differing by at most one, every
    frame in exactly one chunk."""
    if not 1 <= k <= n:
        raise ValueError(f"chunk {k}/{n}: need 1 <= K <= N")
    return _defocus.chunk_frames([int(f) for f in frames], k, n)


def written_with_settings(path: Union[str, os.PathLike], settings_hash: str) -> Tuple[bool, str]:
    """(True, "") when `path` is an image defocus wrote with the settings of
    `settings_hash` (Shot.settings_hash); else (False, what is there instead)."""
    return _defocus.written_with_settings(os.fspath(path), settings_hash)


def _settings_shot(shot: Union[Shot, Dict[str, Any], None], camera: Optional[Dict[str, Any]],
                   settings: Dict[str, Any]) -> Shot:
    if isinstance(shot, dict):  # the camera given in the shot's place
        shot, camera = None, {**shot, **(camera or {})}
    s = Shot() if shot is None else shot.copy()
    for name, value in {**(camera or {}), **settings}.items():
        s._set(name, value)
    return s


def _array(value: Any, what: str, channels: int) -> np.ndarray:
    """`value` (a numpy array or an OpenImageIO.ImageBuf) as C-contiguous
    float32, height x width x channels (height x width for one)."""
    if type(value).__name__ == "ImageBuf" and hasattr(value, "get_pixels"):
        import OpenImageIO as oiio
        if value.nchannels != channels:
            raise ValueError(f"{what}: an ImageBuf of {value.nchannels} channels; "
                             f"expected {channels}")
        value = value.get_pixels(oiio.FLOAT)
        if value is None:
            raise ValueError(f"{what}: the ImageBuf holds no pixels")
        value = value.reshape(value.shape[0], value.shape[1], channels)
    if not isinstance(value, np.ndarray):
        raise ValueError(f"{what}: expected a numpy array or an OpenImageIO.ImageBuf, "
                         f"got {type(value).__name__}")
    if value.dtype != np.float32:
        raise ValueError(f"{what}: dtype {value.dtype}; expected float32 "
                         f"(convert with .astype(numpy.float32))")
    if channels == 1 and value.ndim == 3 and value.shape[2] == 1:
        value = value[:, :, 0]
    expected = "height x width" + ("" if channels == 1 else f" x {channels}")
    if value.ndim != (2 if channels == 1 else 3) or (channels > 1 and value.shape[2] != channels):
        raise ValueError(f"{what}: shape {value.shape}; expected {expected}")
    if value.shape[0] == 0 or value.shape[1] == 0:
        raise ValueError(f"{what}: an empty image, shape {value.shape}")
    return np.ascontiguousarray(value)


def _imagebuf_windows(value: Any) -> Optional[Tuple[int, ...]]:
    """An ImageBuf's data window origin and display window, as _windows
    gives them; None for an array."""
    if type(value).__name__ != "ImageBuf":
        return None
    spec = value.spec()
    return (spec.x, spec.y, spec.full_x, spec.full_y, spec.full_width, spec.full_height)


def _layers(layers: Sequence[Any], what: str) -> List[Tuple[str, np.ndarray, np.ndarray]]:
    out = []
    for i, layer in enumerate(layers):
        name, rgba, z = _layer_parts(layer, i, what)
        rgba = _array(rgba, f"{what}[{i}] rgba", 4)
        z = _array(z, f"{what}[{i}] z", 1)
        if z.shape != rgba.shape[:2]:
            raise ValueError(f"{what}[{i}]: z is {z.shape[1]}x{z.shape[0]}, "
                             f"rgba {rgba.shape[1]}x{rgba.shape[0]}")
        if out and rgba.shape != out[0][1].shape:
            raise ValueError(f"{what}[{i}]: {rgba.shape[1]}x{rgba.shape[0]}, "
                             f"the first layer {out[0][1].shape[1]}x{out[0][1].shape[0]}")
        out.append((str(name), rgba, z))
    if not out:
        raise ValueError(f"{what}: no layers")
    return out


def _layer_parts(layer: Any, i: int, what: str) -> Tuple[Any, Any, Any]:
    """(name, rgba, z) of one layer as render_layers takes it."""
    if isinstance(layer, dict):
        return layer.get("name", f"layer{i}"), layer.get("rgba"), layer.get("z")
    if isinstance(layer, (tuple, list)) and len(layer) in (2, 3):
        if len(layer) == 3 and not isinstance(layer[2], str):
            raise TypeError(f"{what}[{i}]: the third item is the layer's name, a str, not a "
                            f"{type(layer[2]).__name__}")
        return (layer[2] if len(layer) == 3 else f"layer{i}"), layer[0], layer[1]
    raise ValueError(f"{what}[{i}]: expected (rgba, z) or (rgba, z, name)")


def _whole_pixels(value: Any, count: int, what: str) -> Tuple[int, ...]:
    try:
        values = tuple(value)
    except TypeError:
        values = ()
    if len(values) != count or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool)
                                       for v in values):
        form = "(x, y)" if count == 2 else "(x, y, width, height)"
        raise ValueError(f"{what}: expected {form} in whole pixels, got {value!r}")
    return tuple(int(v) for v in values)


def _windows(layers: Sequence[Any], arrays: List[Tuple[str, np.ndarray, np.ndarray]],
             origin: Any, display_window: Any, what: str) -> Tuple[int, ...]:
    """Where the arrays lie, as (x, y, full_x, full_y, full_width,
    full_height): the data window's origin and the display window as given,
    else those of the ImageBufs passed, else (0, 0) and the arrays' extent."""
    bufs = None
    for i, layer in enumerate(layers):
        for part in _layer_parts(layer, i, what)[1:]:
            found = _imagebuf_windows(part)
            if found is not None and bufs is not None and found != bufs:
                raise ValueError(f"{what}[{i}]: an ImageBuf whose data or display window "
                                 f"differs from the first ImageBuf's")
            bufs = bufs or found
    height, width = arrays[0][1].shape[:2]
    xy = _whole_pixels(origin, 2, "origin") if origin is not None else (bufs or (0, 0))[:2]
    if display_window is not None:
        full = _whole_pixels(display_window, 4, "display_window")
        if full[2] <= 0 or full[3] <= 0:
            raise ValueError(f"display_window: {full} is empty")
    else:
        full = bufs[2:] if bufs else (*xy, width, height)
    windows = (*xy, *full)
    if bufs and windows != bufs:
        raise ValueError(f"{what}: origin and display_window {windows} differ from the "
                         f"ImageBufs' {bufs}: give them once")
    return windows


def render_layers(layers: Sequence[Any], shot: Union[Shot, Dict[str, Any], None] = None,
                  frame: Optional[int] = None, crop: bool = False,
                  camera: Optional[Dict[str, Any]] = None,
                  origin: Optional[Tuple[int, int]] = None,
                  display_window: Optional[Tuple[int, int, int, int]] = None,
                  **settings: Any) -> np.ndarray:
    """Renders layers held in memory, as defocus renders the same layers
    from a file.

    layers: (rgba, z) or (rgba, z, name) per layer, in any order (they are
    sorted by depth): rgba premultiplied float32, height x width x 4; z
    planar camera-space depth in metres, float32, height x width. Either may
    be an OpenImageIO.ImageBuf. One layer is a flat render, which is cut
    into depth layers as defocus cuts a file of one part (layers=N sets how
    many); several are layers, spread as they are, as the parts of a
    multi-part EXR.

    The arrays cover the data window, which all layers share: `origin` is
    its top left (x, y), and `display_window` (x, y, width, height) is the
    frame the camera sees, which sets the blur's scale in pixels, as in
    OpenImageIO's ImageSpec. By default they are those of the ImageBufs
    given, else (0, 0) and the arrays' own extent: pass both for a render
    with overscan.

    The settings come from `shot` (a Shot, whose inputs are unused, or a
    dict of settings), then `camera` (a dict), then keywords:
    render_layers(layers, focal=85, fstop=1.4, focus=3.0, aperture="disc").
    Returns what render() returns.
    """
    s = _settings_shot(shot, camera, settings)
    arrays = _layers(layers, "layers")
    windows = _windows(layers, arrays, origin, display_window, "layers")
    return _defocus.render_layers(arrays, windows, s._native, _frame(frame),
                                  _flag(crop, "crop"))[0]


def decompose(rgba: Any, z: Any, shot: Union[Shot, Dict[str, Any], None] = None,
              frame: Optional[int] = None,
              camera: Optional[Dict[str, Any]] = None,
              origin: Optional[Tuple[int, int]] = None,
              display_window: Optional[Tuple[int, int, int, int]] = None,
              **settings: Any) -> List[Tuple[np.ndarray, np.ndarray, str]]:
    """Cuts a flat render (premultiplied RGBA and depth, float32 arrays or
    ImageBufs) into depth layers, as defocus does for a flat input under
    the camera (settings, origin and display_window as for render_layers;
    layers=N asks for N).

    Returns (rgba, z, name) per layer, back to front, each over the
    render's data window (transparent where the layer has nothing), in
    scene-linear light: render_layers() takes them as they are, with the
    same origin and display_window.
    """
    s = _settings_shot(shot, camera, settings)
    given = [(rgba, z, "render")]
    arrays = _layers(given, "render")
    windows = _windows(given, arrays, origin, display_window, "render")
    layers = _defocus.decompose(arrays, windows, s._native, _frame(frame))
    return [(rgba_, z_, name) for name, rgba_, z_ in layers]
