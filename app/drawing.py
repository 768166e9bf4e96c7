"""What the window draws of the runs: the ball (or every run's ball) at the moment shown, its
trail and close-up, the events reached so far (markers in the view and on the time slider), the
readouts, the plots and the progress bar; before any run, the ball at its start.

An event (a lift-off, a landing, a slip, a grip) is marked once playback reaches it, on screen
and in an exported video alike, unless the View menu's Show Future Events asks for all of them
from the start (a preference).

The run controller says when the moment shown has moved (``frameReady``); ``draw`` shows it,
and brings the plots up to it at most every ``PLOT_INTERVAL``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from rollball import Scene, Status
from rollball.geometry import unit_normal
from rollball.trajectory import CENTER, CONTACT, R, SLIDING

from .budget import causes_on, floor_energy
from .closeup import inset_place
from .contact_view import KIND_COLORS, beyond_2011, rgba, trail_colors
from .controller import RUNNING
from .view3d import MARK_FILL

PLOT_INTERVAL = 0.1   # s between plot updates while playing (at most 10/s; at every frame where frames are slower)


class Drawing:
    """Draws ``window``'s runs (a ``MainWindow``: its controller, view, close-up, readouts,
    time slider, plots and progress bar)."""

    def __init__(self, window):
        self.window = window
        self.drawn_index = -1                # the rows the view shows
        self.plotted_at = -math.inf          # when the plots were last brought up to the shown time
        self.marked: tuple | None = ()      # the events marked in the view (run, time, kind) as last drawn
        self.show_future = window.preferences.show_future_events()   # (the time slider is told by the window)

    def clear(self) -> None:
        """No run: the ball at the start of the scene, empty plots and time slider."""
        w = self.window
        self.drawn_index = -1
        w.view.set_runs(None)
        w.readouts.set_runs([None])
        scene = w.scene
        w.readouts.show_contact(scene is not None and beyond_2011(scene))
        w.plots.show_contact(scene is not None and beyond_2011(scene))
        w.plots.landings = []
        causes = causes_on(scene) if scene is not None and w.landscape is not None else ()
        w.plots.set_budget(causes, floor_energy(scene, w.landscape) if causes else 0.0)
        if scene is not None and w.landscape is not None:
            self.draw_start(scene)
        w.plots.show_run(None, 0)
        w.plots.set_cursor(None)
        w.timeline.set_span(0.0)
        self.marked = ()
        w.view.set_marked(np.zeros((0, 3)), np.zeros((0, 4)))
        w.view.set_trail(np.zeros((0, 3)))
        w.progress.setValue(0)

    def draw_start(self, scene: Scene) -> None:
        """The ball at its start position, before any run."""
        w = self.window
        s, r = scene.start, scene.ball.radius
        d = w.landscape.evaluate(s.x, s.y)
        valid = bool(np.all(np.isfinite(d)))
        w.view.ball.setVisible(valid)   # no ball left hanging where the start was
        if not valid:
            w.start_editing.hide()
            w.show_message(f"The landscape cannot be evaluated at the start point ({s.x:g}, {s.y:g})",
                           warning=True)
            return
        center = np.array([s.x, s.y, d[0]]) + r * unit_normal(d)
        w.view.set_ball(center, np.eye(3), r)
        w.start_editing.show(scene, center, unit_normal(d), d[1:3])   # the handles, the path's preview
        self._show_closeup_at(center, np.eye(3), np.array([s.x, s.y]), np.zeros((0, 3)))
        w.readouts.clear()

    def draw(self, force: bool = False) -> None:
        w = self.window
        runs, t = w.controller.runs, w.controller.play_time
        if not runs or all(len(run.buffer) == 0 for run in runs):
            return
        indices = tuple(run.index_at(t) for run in runs)
        self.mark_events(t)
        if indices == self.drawn_index and not force:
            return  # the same rows as the last frame
        self.drawn_index = indices
        radius = runs[0].simulation.scene.ball.radius
        followed = w.view.followed
        for k, (run, i) in enumerate(zip(runs, indices)):
            if len(run.buffer):
                row = run.buffer.rows[i]
                picked = run.buffer.trail_rows(i)
                trail = run.buffer.trail(i, lift=0.3, picked=picked)   # 0.3 r above the contact point
                w.view.set_ball(row[CENTER], row[R].reshape(3, 3), radius, k)
                # coloured by the contact's mode (in compare mode, shades of the run's colour)
                colors = trail_colors(run.buffer.mode[picked], run.color)
                w.view.set_trail(trail, k, colors)
                if run.color is None:   # one run: its ring tinted while it slides
                    sliding = run.buffer.mode_of(i) == SLIDING
                    w.view.set_mark_fill((*colors[-1][:3], MARK_FILL[3]) if sliding else MARK_FILL)
                if k == followed:
                    self._show_closeup_at(row[CENTER], row[R].reshape(3, 3), row[CONTACT], trail, run.color, colors)
                w.readouts.show_row(k, run.buffer, i)
        followed = w.compare.followed if w.compare.followed < len(runs) else 0
        if len(runs[followed].buffer):   # the time of the moment drawn, as its readout says it
            w.timeline.set_time(t, shown=float(runs[followed].buffer.t[indices[followed]]))
        if force or time.perf_counter() - self.plotted_at >= PLOT_INTERVAL:
            self.plot()   # in the same frame as the 3-D view: the window is composed once
        shown = min(float(run.buffer.t[i]) for run, i in zip(runs, indices) if len(run.buffer))
        span = w.controller.t_end
        if w.controller.computed and all(run.simulation.status is Status.OK for run in runs):
            span = w.controller.end_time   # a run that came to rest ended there: played to it is all of it
        w.progress.setValue(int(round(1000 * min(1.0, shown / span))))

    def plot(self) -> None:
        """Bring the plots, and the time line's computed span and events, up to the shown time."""
        w = self.window
        self.plotted_at = time.perf_counter()
        runs, t = w.controller.runs, w.controller.play_time
        if w.compare.active:
            w.compare.error_plots.show_time(t, w.compare.followed)
        elif runs and len(runs[0].buffer):
            # while playing, the curves grow with the ball; otherwise they show all that is computed
            buffer = runs[0].buffer
            i = buffer.index_at(t)
            w.plots.landings = [c.time for c in runs[0].transitions if c.kind == "landing"]
            shown = i if w.controller.state == RUNNING else len(buffer) - 1
            w.plots.show_run(buffer, shown)
            w.plots.show_budget(runs[0].trajectory(), shown, i)
            w.plots.set_cursor(buffer.t[i])
        if runs:
            w.timeline.set_available(w.controller.end_time)
            w.runs.show_events()

    def events(self, run, t: float) -> list[tuple[float, str, float, float]]:
        """A run's events to mark at time t: (time, kind, x, y) of its lift-off (a glued ball's,
        where it would leave the surface) and its transitions, those up to t (all of them with
        ``show_future``)."""
        out = []
        liftoff = run.simulation.liftoff_time
        if run.glued and liftoff is not None and len(run.buffer):
            out.append((liftoff, "liftoff", *run.buffer.point_at(liftoff)[:2]))
        out += [(c.time, c.kind, c.x, c.y) for c in run.transitions]
        return [e for e in out if self.show_future or e[0] <= t]

    def mark_events(self, t: float) -> None:
        """Mark in the view every run's events reached at time t (changed only when they change),
        over the surface as the trail is (0.3 r along the normal)."""
        w = self.window
        runs = w.controller.runs
        marked = [(k, e) for k, run in enumerate(runs) for e in self.events(run, t)]
        key = tuple((k, e[0], e[1]) for k, e in marked)
        if key == self.marked:
            return
        self.marked = key
        points, colors = [], []
        for k, (_, kind, x, y) in marked:
            d = runs[k].buffer.landscape.evaluate(x, y)
            if np.all(np.isfinite(d[:3])):
                points.append(np.array([x, y, d[0]]) + 0.3 * runs[k].buffer.radius * unit_normal(d))
                colors.append(rgba(KIND_COLORS[kind]))
        w.view.set_marked(np.array(points).reshape(-1, 3), np.array(colors).reshape(-1, 4))

    def show_future_events(self, on: bool) -> None:
        """Every event marked from the start (on), or each once playback reaches it; remembered."""
        self.show_future = on
        self.window.preferences.set_show_future_events(on)
        self.window.timeline.set_show_future(on)
        self.marked = None   # marked again, whatever they were
        if self.window.controller.runs:
            self.mark_events(self.window.controller.play_time)
            self.window.view.update()

    def follow(self, on: bool) -> None:
        """The camera follows the ball (in compare mode, the followed run's)."""
        w = self.window
        w.view.set_follow(on, w.scene.ball.radius if on and w.scene else None, index=w.compare.followed)

    # -- the close-up ----------------------------------------------------------------

    def show_closeup(self, on: bool) -> None:
        w = self.window
        w.closeup_frame.setVisible(on)
        self.place_closeup()
        if not on:
            return
        if w.controller.runs:
            self.draw(force=True)
        elif w.scene is not None and w.landscape is not None:
            self.draw_start(w.scene)

    def place_closeup(self) -> None:
        """In a corner of the view where it covers none of the axes, their numbers and names
        (``closeup.inset_place``: the top right one first, 0.3 of the view's width; smaller if
        need be); placed again whenever the axes move on screen (``SceneView.axesPlaced``)."""
        w = self.window
        labels, lines = w.view.taken
        frame = w.closeup_frame
        place = inset_place((w.view.width(), w.view.height()), labels, lines,
                            frame.geometry() if frame.width() > 0 else None)
        if place != frame.geometry():
            frame.setGeometry(place)

    def _show_closeup_at(self, center, R, contact, trail, color: str | None = None, colors=None) -> None:
        w = self.window
        if w.closeup.isVisible():
            w.closeup.show_ball(center, R, contact, trail, w.view.opts["azimuth"], w.view.opts["elevation"], color,
                                colors)
