"""The live path preview: the first seconds of the path, computed in the background while the
scene is edited (the formula typed, a slider dragged, the start moved) and drawn as a thin line
on the surface, coloured by the mode it predicts (rolling, sliding, flying: the trail's colours).

Each preview is a short run of the scene (``PREVIEW_SECONDS`` at most) with a cheap, accurate
method (dopri5 at loose tolerances, a few hundred rows), in a ``worker.Worker``. A newer edit
cancels the preview being computed (between chunks of ``CHUNK_STEPS`` steps; the kernel
releases the GIL meanwhile, so typing never waits for it) and is computed when that one has
ended: only the latest scene's preview is ever drawn.
"""

from __future__ import annotations

import dataclasses
from functools import partial

import numpy as np
from PySide6 import QtCore

from rollball import Scene, Simulation
from rollball.comparison import Cancelled
from rollball.trajectory import CENTER, T

from .worker import Worker, one_line

PREVIEW_SECONDS = 3.0     # simulated seconds shown ahead
PREVIEW_ROWS = 300        # points of the line
PREVIEW_METHOD = "dopri5"
RTOL, ATOL = 1e-6, 1e-9   # loose for a picture, tight enough to follow the true path for seconds
CHUNK_STEPS = 100         # steps between looks at the cancel flag


@dataclasses.dataclass(frozen=True)
class Preview:
    """The preview of ``scene``: ``points`` (n, 3), the ball's centre along the path (drawn
    there, a radius above the surface, it is never hidden by the grid lines), at ``times`` (n,)
    to time ``t_end``, with the contact's ``modes`` there (n,; positions in ``trajectory.MODES``);
    ``status`` how the short run ended (ok, or where it stopped)."""
    scene: Scene
    points: np.ndarray
    t_end: float
    status: str
    times: np.ndarray
    modes: np.ndarray


def preview_scene(scene: Scene) -> Scene:
    """The scene a preview runs: its first seconds, with the preview's method."""
    return dataclasses.replace(scene, duration=min(scene.duration, PREVIEW_SECONDS),
                               integrator=dataclasses.replace(scene.integrator, method=PREVIEW_METHOD,
                                                              munthe_kaas=True, rtol=RTOL, atol=ATOL))


def compute(scene: Scene, cancel=None) -> Preview:
    """The preview of ``scene`` (``Cancelled`` once ``cancel``, a threading.Event, is set)."""
    short = preview_scene(scene)
    simulation = Simulation(short, record_dt=short.duration / PREVIEW_ROWS)
    simulation.judge_energy = False    # a picture: no verdict on the energy
    while not simulation.done:
        if cancel is not None and cancel.is_set():
            raise Cancelled
        simulation.advance(CHUNK_STEPS, rows=False)
    rows = simulation.rows
    points = rows[:, CENTER].copy()
    t_end = float(rows[-1, T]) if len(rows) else 0.0
    modes = simulation.modes if hasattr(type(simulation), "modes") else np.zeros(len(rows), dtype=np.int8)
    return Preview(scene, points, t_end, simulation.status.value, rows[:, T].copy(), np.array(modes[:len(rows)]))


class PathPreview(QtCore.QObject):
    """One preview computed at a time. ``request(scene)`` asks for the scene's preview (a
    preview under way is cancelled; the latest request follows it); ``ready(preview)`` brings
    it, only for the latest scene requested, ``failed(message)`` says why there is none;
    ``clear()`` drops what is asked for."""

    ready = QtCore.Signal(object)
    failed = QtCore.Signal(str)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.worker: Worker | None = None
        self.computing: Scene | None = None   # the scene the worker computes
        self.wanted: Scene | None = None      # the latest scene asked for
        self.computed = 0                     # previews computed to the end
        self.cancelled = 0                    # previews cancelled for a newer one

    def request(self, scene: Scene) -> None:
        if self.worker is not None and scene == self.computing and not self.worker.cancel_event.is_set():
            self.wanted = scene               # already under way
            return
        self.wanted = scene
        if self.worker is None:
            self._start(scene)
        else:
            self.worker.cancel(wait=False)    # it ends within a chunk; _ended starts the latest

    def clear(self) -> None:
        self.wanted = None
        if self.worker is not None:
            self.worker.cancel(wait=False)

    @property
    def busy(self) -> bool:
        return self.worker is not None

    def _start(self, scene: Scene) -> None:
        worker = Worker(lambda _progress, cancel: compute(scene, cancel), describe=one_line, name="preview")
        worker.done.connect(self._done)
        worker.failed.connect(self._failed)
        worker.cancelled.connect(self._cancelled)
        worker.ended.connect(partial(self._ended, worker))
        self.worker, self.computing = worker, scene
        worker.start()

    def _done(self, preview: Preview) -> None:
        self.computed += 1
        if preview.scene == self.wanted:
            self.ready.emit(preview)

    def _failed(self, message: str) -> None:
        if self.computing == self.wanted:
            self.failed.emit(message)

    def _cancelled(self) -> None:
        self.cancelled += 1

    def _ended(self, worker: Worker) -> None:
        if worker is not self.worker:   # let go of already (shutdown)
            return
        ended = self.computing
        cancelled = worker.cancel_event.is_set()
        self.worker = self.computing = None   # the worker lets go of itself
        if self.wanted is not None and (self.wanted != ended or cancelled):
            self._start(self.wanted)

    def shutdown(self) -> None:
        """Cancel and wait (the window closes)."""
        self.wanted = None
        if self.worker is not None:
            self.worker.cancel()   # bounded
            self.worker = self.computing = None
