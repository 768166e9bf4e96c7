"""How the app shows the contact's modes (rolling, sliding, flying) and its transitions (slip,
grip, lift-off, landing): the colours, declared once, and the pieces the views use — the
trail's colour per point, the markers on the time slider, the words said as playback passes
a transition, the shaded spans of the plots.

Drawing only: the modes and transitions come with the run (``Simulation.modes``,
``Simulation.transitions``).
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg

from rollball.trajectory import FLYING, MODES, RESTING, ROLLING, SLIDING

from .timeline import Marker

# The trail's colour by mode: told apart by lightness as well as hue (the Okabe–Ito colours
# that colour-blind readers tell apart): vermillion rolling (the 2011 trail was red), sky blue sliding,
# white flying, yellow resting; each drawn over a dark edge that keeps it readable on every colour of
# the surface.
MODE_COLORS = {ROLLING: "#d55e00", SLIDING: "#56b4e9", FLYING: "#ffffff", RESTING: "#f0e442"}
MODE_WORDS = {ROLLING: "rolling", SLIDING: "sliding", FLYING: "flying", RESTING: "resting"}
# The plots' spans (behind the curves): none rolling, sliding in the trail's sky blue, flight grey,
# resting yellow; pale.
SPAN_COLORS = {SLIDING: (86, 180, 233, 60), FLYING: (120, 120, 120, 45), RESTING: (240, 228, 66, 50)}
# Markers by kind of transition (slider, 3-D view); lift-off keeps the orange it always had.
KIND_COLORS = {"slip": "#0072b2", "grip": "#009e73", "liftoff": "#ff8c00", "landing": "#cc79a7", "rest": "#f0e442"}
KIND_WORDS = {"slip": "slip", "grip": "grip", "liftoff": "lift-off", "landing": "landing", "rest": "rest"}
SHADES = {ROLLING: 1.0, SLIDING: 0.55, FLYING: None, RESTING: 0.8}   # compare mode: the run's colour, darker, pale
assert set(MODE_COLORS) == set(range(len(MODES)))


def beyond_2011(scene) -> bool:
    """Whether a scene's ball may slip or fly (else it rolls glued to the surface, as in 2011)."""
    return scene.contact.friction is not None or scene.contact.after_liftoff == "fly"


def rgba(color: str) -> np.ndarray:
    return np.array(pg.mkColor(color).getRgbF(), dtype=float)


def trail_colors(codes: np.ndarray, run_color: str | None = None) -> np.ndarray:
    """(n, 4) colours of a trail's points by their modes' codes: ``MODE_COLORS``, or in compare
    mode shades of the run's own colour (rolling as it is, sliding darker, flying pale)."""
    if run_color is None:
        table = np.array([rgba(MODE_COLORS[k]) for k in range(len(MODES))])
    else:
        base = rgba(run_color)
        table = np.empty((len(MODES), 4))
        for k, shade in SHADES.items():
            table[k, :3] = 0.35 * base[:3] + 0.65 if shade is None else shade * base[:3]
            table[k, 3] = 1.0
    return table[np.asarray(codes, dtype=int)]


def sentence(kind: str, t: float, who: str = "") -> str:
    """What the status bar says as playback passes a transition."""
    words = {"slip": "the ball slips: rolling would need more friction than μ F·N",
             "grip": "the slip has stopped: the ball rolls",
             "liftoff": "the ball leaves the surface and flies",
             "landing": "the ball lands",
             "rest": "the ball comes to rest"}[kind]
    return f"{who}{KIND_WORDS[kind].capitalize()} at t = {t:.4g} s: {words}"


def summary(transitions, listed: int = 3) -> str:
    """The transitions of a finished run in a few words: each with its time where there are at
    most ``listed`` ("; lift-off at t = 0.4465 s, landing at t = 0.8919 s (2.3 J lost)"), else
    counted ("; 2 lift-offs, 5 landings (3.1 J lost)"); "" for none. A landing the ball bounces
    from (the next change is another landing, no lift-off between) is counted as a bounce too:
    one lift-off and nine landings is no miscount ("9 landings (8 bounces, 3.35 J lost)")."""
    def lost(changes) -> str:
        bounces = sum(1 for c, after in zip(transitions, transitions[1:])
                      if c.kind == "landing" and after.kind == "landing") if changes[0].kind == "landing" else 0
        counted = (f"{bounces} bounce{'s' if bounces > 1 else ''}, " if bounces and len(changes) > 1 else "")
        return f" ({counted}{sum(c.energy_lost or 0.0 for c in changes):.3g} J lost)"

    if len(transitions) <= listed:
        return "".join(("; " if i == 0 else ", ") + f"{KIND_WORDS[c.kind]} at t = {c.time:.4g} s"
                       + (lost([c]) if c.kind == "landing" else "") for i, c in enumerate(transitions))
    parts = []
    for kind, word in KIND_WORDS.items():
        changes = [c for c in transitions if c.kind == kind]
        if changes:
            parts.append(f"{len(changes)} {word}{'s' if len(changes) > 1 else ''}"
                         + (lost(changes) if kind == "landing" else ""))
    return "; " + ", ".join(parts)


def markers(transitions, label: str = "") -> list[Marker]:
    """The slider's markers of a run's transitions (``label``: the run's name, in compare mode)."""
    who = f"{label}: " if label else ""
    out = []
    for change in transitions:
        text = f"{who}{KIND_WORDS[change.kind]} at t = {change.time:.4g} s"
        if change.kind == "landing" and change.impact_speed is not None:
            text += f" ({change.impact_speed:.3g} m/s, {change.energy_lost:.3g} J lost)"
        out.append(Marker(change.time, KIND_COLORS[change.kind], text,
                          f"{KIND_WORDS[change.kind]} {change.time:.3g} s", KIND_WORDS[change.kind]))
    return out


def spans(t: np.ndarray, codes: np.ndarray) -> list[tuple[float, float, int]]:
    """(start, end, mode) of each stretch of rows not rolling, from row times and mode codes."""
    codes = np.asarray(codes)
    if not len(codes):
        return []
    edges = np.flatnonzero(np.diff(codes)) + 1
    starts, ends = np.r_[0, edges], np.r_[edges, len(codes)]
    return [(float(t[a]), float(t[min(b, len(t) - 1)]), int(codes[a])) for a, b in zip(starts, ends)
            if codes[a] != ROLLING]


class ModeSpans:
    """Shaded time spans on a pyqtgraph plot where the run slides or flies (behind its curves),
    with the mode's name in the tooltip, and a line at each landing (one flight can follow another
    at once: a bounce)."""

    def __init__(self, plot: pg.PlotItem):
        self.plot = plot
        self.items: list[pg.LinearRegionItem] = []
        self.shown: list[tuple[float, float, int]] = []
        self.lines: list[pg.InfiniteLine] = []

    def show(self, t: np.ndarray, codes: np.ndarray, landings=()) -> None:
        """Spans from rows' times and modes; ``landings``: times, those up to the last row shown."""
        last = float(t[-1]) if len(t) else -np.inf
        shown_landings = [x for x in landings if x <= last]
        if [line.value() for line in self.lines] != shown_landings:
            for line in self.lines:
                self.plot.removeItem(line)
            self.lines = [pg.InfiniteLine(pos=x, angle=90, pen=pg.mkPen(KIND_COLORS["landing"], width=2))
                          for x in shown_landings]
            for line in self.lines:
                line.setToolTip(f"landing at t = {line.value():.4g} s")
                self.plot.addItem(line, ignoreBounds=True)
        wanted = spans(t, codes)
        if wanted == self.shown:
            return
        self.shown = wanted
        while len(self.items) > len(wanted):
            self.plot.removeItem(self.items.pop())
        while len(self.items) < len(wanted):
            item = pg.LinearRegionItem(movable=False, pen=pg.mkPen(None))
            item.setZValue(-10)   # behind the curves
            self.plot.addItem(item, ignoreBounds=True)
            self.items.append(item)
        for item, (a, b, mode) in zip(self.items, wanted):
            item.setRegion((a, b))
            item.setBrush(pg.mkBrush(SPAN_COLORS[mode]))
            item.setToolTip(f"{MODE_WORDS[mode]} from t = {a:.4g} to {b:.4g} s")
