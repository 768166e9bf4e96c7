"""Animation files: MP4 (H.264 through imageio-ffmpeg, which ships its own ffmpeg) or GIF
(through imageio's Pillow plugin), written frame by frame and put in place atomically.

No Qt here: frames arrive as RGB arrays. The encoder writes into a private staging folder;
``finish`` copies the result through ``rollball.files.atomic_write``, so a cancelled or failed
export leaves any old file at the path untouched and no partial file behind.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from rollball.files import atomic_write

from .formats import MAX_FPS, format_of

GIF_COLORS = 256
SHADES = (0.35, 0.55, 0.75, 0.9, 1.0)   # shaded surfaces show an accent colour at these brightnesses


def frame_times(t0: float, t1: float, fps: float) -> np.ndarray:
    """The simulated times of the frames from t0 to t1 inclusive, ``fps`` per simulated second."""
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 >= t0):
        raise ValueError(f"time span {t0:g} to {t1:g} s is not a span")
    if not (math.isfinite(fps) and 0 < fps <= MAX_FPS):
        raise ValueError(f"frames per second must be in (0, {MAX_FPS}], not {fps:g}")
    n = int(math.floor((t1 - t0) * fps + 1e-9)) + 1
    return t0 + np.arange(n) / fps


def even_size(width: int, height: int) -> tuple[int, int]:
    """H.264 in yuv420p needs even sides."""
    return width - width % 2, height - height % 2


def gif_palette(first, accents: np.ndarray):
    """One palette for a whole GIF: the first frame's colours plus shades of the accents."""
    from PIL import Image

    shades = (np.outer(SHADES, np.ones(3))[None, :, :] * accents[:, None, :]).reshape(-1, 3)
    extra = np.round(255 * np.clip(shades, 0, 1)).astype(int)
    base = first.quantize(GIF_COLORS - len(extra), dither=Image.Dither.NONE)
    palette = Image.new("P", (1, 1))
    palette.putpalette(base.getpalette()[: 3 * (GIF_COLORS - len(extra))] + extra.ravel().tolist())
    return palette


class AnimationWriter:
    """Write frames of one size to ``path`` (.mp4 or .gif) at ``fps`` frames per second of video.

    Use ``add(frame)`` for each (height, width, 3 or 4) uint8 frame, then ``finish()``;
    ``abort()`` (or an exception inside a ``with`` block) drops everything written. ``accents``:
    colours (RGB in 0..1) that may appear after the first frame and must keep their hue in a GIF
    (trail, markers, the ball's stripes); each is kept in several shades."""

    def __init__(self, path: str | os.PathLike, size: tuple[int, int], fps: float, accents=(), keep=()):
        self.path = Path(path)
        self.keep = list(keep)   # paths never written over (the open scene)
        self.kind = format_of(path)
        self.size = even_size(*size) if self.kind == ".mp4" else (int(size[0]), int(size[1]))
        if min(self.size) < 2:
            raise ValueError(f"frame size {size[0]}×{size[1]} is too small")
        self.fps = float(fps)
        self.frames = 0
        self.accents = np.asarray(accents, dtype=float).reshape(-1, 3)
        self._staging = tempfile.TemporaryDirectory(prefix="rollball-animation-")
        self._file = Path(self._staging.name) / f"animation{self.kind}"
        if self.kind == ".mp4":
            import imageio_ffmpeg

            self._encoder = imageio_ffmpeg.write_frames(
                str(self._file), self.size, fps=self.fps, codec="libx264", quality=8, macro_block_size=1,
                output_params=["-movflags", "+faststart"])
            self._encoder.send(None)
        else:
            import imageio.v3 as iio

            self._encoder = iio.imopen(self._file, "w", plugin="pillow", extension=".gif")
            self._palette = None

    def add(self, frame: np.ndarray) -> None:
        w, h = self.size
        if frame.ndim != 3 or frame.shape[0] < h or frame.shape[1] < w:
            raise ValueError(f"frame of shape {frame.shape} for a {w}×{h} animation")
        rgb = np.ascontiguousarray(frame[:h, :w, :3], dtype=np.uint8)
        if self.kind == ".mp4":
            self._encoder.send(rgb)
        else:
            # One palette for all frames, from the first, without dithering: the parts that do not
            # change stay identical from frame to frame, so GIF stores only what moved.
            from PIL import Image

            picture = Image.fromarray(rgb)
            if self._palette is None:
                self._palette = gif_palette(picture, self.accents)
            indexed = picture.quantize(palette=self._palette, dither=Image.Dither.NONE).convert("RGB")
            # delays in whole hundredths of a second: say so with a duration that GIF can hold
            self._encoder.write(np.asarray(indexed), duration=10 * round(100 / self.fps), loop=0)
        self.frames += 1

    def finish(self) -> Path:
        """Close the encoder and put the file at ``path`` atomically."""
        try:
            self._encoder.close()
            with open(self._file, "rb") as source:
                atomic_write(self.path, lambda stream: shutil.copyfileobj(source, stream), binary=True,
                             keep=self.keep)
        finally:
            self._staging.cleanup()
        return self.path

    def abort(self) -> None:
        try:
            self._encoder.close()
        except Exception:  # a half-written staging file is thrown away anyway
            pass
        self._staging.cleanup()

    def __enter__(self):
        return self

    def __exit__(self, kind, value, traceback):
        if kind is not None:
            self.abort()


def record(path: str | os.PathLike, times: np.ndarray, fps: float, size: tuple[int, int], show, frame,
           progress=None, accents=(), keep=()) -> bool:
    """Write one frame per time: ``show(t)`` puts that moment in place, ``frame()`` returns it as
    an RGB array of ``size``. ``progress(done, total)`` is called after every frame; when it
    returns False the export is cancelled, nothing is written and False is returned. ``keep``:
    paths the file may not replace."""
    with AnimationWriter(path, size, fps, accents, keep) as writer:
        for k, t in enumerate(times):
            show(float(t))
            writer.add(frame())
            if progress is not None and progress(k + 1, len(times)) is False:
                writer.abort()
                return False
        writer.finish()
    return True
