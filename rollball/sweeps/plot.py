"""sweep.png: a map over two varied keys coloured by one outcome, or curves against one key.

Runs without a value of the coloured outcome get a colour of their own that says why (no
lift-off, does not fit, non-finite, refused scene), and the runs where the ball stopped
fitting are hatched whatever their colour, so those regions read at a glance.
"""

from __future__ import annotations

import io
import math
import textwrap
import warnings

import numpy as np

from .. import kernel
from ..files import atomic_write_bytes
from .grid import KEYS
from ..modes import MODES, ROLLING
from .outcomes import (CONTACT_OUTCOMES, INVALID, NOT_RUN, O_END_MODE, O_FIRST_GRIP, O_FIRST_SLIP, O_LANDINGS,
                       O_REST_TIME, OUTCOMES, REST_OUTCOMES)

UNITS = {"t_reached": "s", "liftoff_time": "s", "x_end": "m", "y_end": "m", "energy_drift": "relative",
         "min_normal_force": "N", "max_speed": "m/s", "path_length": "m", "first_slip_time": "s",
         "first_grip_time": "s", "rest_x": "m", "rest_y": "m", "rest_time": "s"}

# Colours of the runs that have no value to colour by, with their legend text.
_CATEGORY = {
    kernel.OK: ("#d9d9d9", None),                 # the legend text depends on the outcome
    kernel.DOES_NOT_FIT: ("#202020", "ball does not fit"),
    kernel.NONFINITE: ("#e7298a", "non-finite"),
    INVALID: ("#ffffff", "scene refused"),
    NOT_RUN: ("#f4f4f4", "not run (stopped)"),
}


# What a run without a value of the outcome coloured by did (when it ran to its end).
_NO_VALUE = {"liftoff_time": "no lift-off", "rest_x": "never rests", "rest_y": "never rests",
             "rest_time": "never rests", "basin": "never rests"}
# The basins' colours, minimum by minimum (matplotlib's tab10 without its grey), and basin 0's.
BASIN_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#bcbd22",
                 "#17becf")
BASIN_NONE = "#7f7f7f"
TITLE_CHARACTERS = 13   # characters of the figure's title a line holds per inch of its width
LAYOUT_PAD = 0.4        # font sizes between the title, the plots and their labels


def label(name: str) -> str:
    unit = KEYS.get(name) or UNITS.get(name)
    return f"{name} ({unit})" if unit else name


def _edges(centres: np.ndarray) -> np.ndarray:
    """Cell edges around sorted centres (half-way between neighbours)."""
    if len(centres) == 1:
        half = 0.5 * max(abs(centres[0]) * 0.1, 1e-9)
        return np.array([centres[0] - half, centres[0] + half])
    mid = 0.5 * (centres[1:] + centres[:-1])
    return np.concatenate([[2 * centres[0] - mid[0]], mid, [2 * centres[-1] - mid[-1]]])


def figure(table, path, color: str = "liftoff_time") -> bool:
    """Draw the table's figure to ``path`` (atomically); False when there is none to draw:
    matplotlib missing or more than two varied keys."""
    data = figure_png(table, color)
    if data is None:
        return False
    atomic_write_bytes(path, data)
    return True


def figure_png(table, color: str = "liftoff_time") -> bytes | None:
    """The table's figure as PNG bytes; None when there is none to draw: matplotlib missing or
    more than two varied keys. Matplotlib's warnings (a log scale with nothing positive, a
    layout that does not fit) are its own business: they do not reach the user."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return _figure_png(table, color)


def _figure_png(table, color):
    fig = _figure(table, color)
    if fig is None:
        return None
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=130, bbox_inches="tight", pad_inches=0.15)   # (legends below too)
    import matplotlib.pyplot as plt
    plt.close(fig)
    return buffer.getvalue()


def _figure(table, color):
    """The table's figure, laid out (a matplotlib Figure); None as for ``figure_png``."""
    if color not in OUTCOMES:
        raise ValueError(f"cannot colour by {color!r}; the outcomes: {', '.join(OUTCOMES)}")
    if len(table.keys) > 2:
        return None
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    if len(table.keys) == 2:
        fig = _map(plt, table, color)
    else:
        fig = _curves(plt, table, color)
    scene = table.scene
    runs = (f"{len(table):,} runs of {scene.duration:g} s, {scene.integrator.method} dt {scene.integrator.dt:g} s"
            f"{' (stopped early)' if table.partial else ''}")
    # (a long formula takes lines of its own rather than run off the figure)
    lines = textwrap.wrap(f"z = {scene.landscape}, {runs}", int(TITLE_CHARACTERS * fig.get_figwidth()),
                          break_long_words=True)
    title = "\n".join(lines + [f"{table.seconds:.1f} s wall on {table.workers} "
                               f"{'Dask workers' if table.scheduler else 'local threads'}, {table.machine}"])
    # the title at the figure's top edge; the layout makes room for it as drawn, LAYOUT_PAD above
    # and below it (a rect kept for its lines counted them twice: a white band under the title)
    fig.suptitle(title, y=1.0, va="top", fontsize=9, parse_math=False, usetex=False)
    fig.tight_layout(pad=LAYOUT_PAD)
    return fig


def _map(plt, table, color):
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    (kx, ky), (ax_x, ax_y) = table.keys, table.grid.axes
    shape = table.grid.shape
    order_x, order_y = np.argsort(ax_x), np.argsort(ax_y)
    value = table[color].reshape(shape)[np.ix_(order_x, order_y)].T   # rows: y, columns: x
    codes = table.codes.reshape(shape)[np.ix_(order_x, order_y)].T
    xe, ye = _edges(ax_x[order_x]), _edges(ax_y[order_y])
    fig, ax = plt.subplots(figsize=(8.0, 6.0))
    handles = []
    if color == "basin":
        handles += _basins(ax, table, xe, ye, value)
    else:
        mesh = ax.pcolormesh(xe, ye, np.ma.masked_invalid(value), cmap="viridis", shading="flat")
        fig.colorbar(mesh, ax=ax, label=label(color))
    missing = np.isnan(value)
    for code, (colour, text) in _CATEGORY.items():
        cells = missing & (codes == code)
        if not cells.any():
            continue
        text = text or _NO_VALUE.get(color, f"no {color}")
        ax.pcolormesh(xe, ye, np.ma.masked_where(~cells, np.zeros_like(value)),
                      cmap=ListedColormap([colour]), shading="flat")
        handles.append(Patch(facecolor=colour, edgecolor="0.5", label=text))
    unfit = codes == kernel.DOES_NOT_FIT
    if unfit.any() and len(ax_x) > 1 and len(ax_y) > 1:
        ax.contourf(ax_x[order_x], ax_y[order_y], unfit.astype(float), levels=[0.5, 1.5],
                    colors="none", hatches=["////"])
        handles.append(Patch(facecolor="none", edgecolor="k", hatch="////", label="does not fit (stopped)"))
    if handles:
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0.0, -0.1), ncol=2 if color == "basin" else 4,
                  fontsize=8, frameon=False)
    ax.set_xlabel(label(kx))
    ax.set_ylabel(label(ky))
    return fig


def _basins(ax, table, xe, ye, value) -> list:
    """The map of basins: a colour for each minimum, grey for basin 0; with start.x × start.y
    the minima are marked too. Returns the legend's entries: each minimum's number, place and
    height, and basin 0's."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    minima = table.minima or ()
    colours = [BASIN_NONE] + [BASIN_COLOURS[k % len(BASIN_COLOURS)] for k in range(len(minima))]
    ax.pcolormesh(xe, ye, np.ma.masked_invalid(value), cmap=ListedColormap(colours), vmin=-0.5,
                  vmax=len(minima) + 0.5, shading="flat")
    handles = [Patch(facecolor=colours[m.number], edgecolor="0.5",
                     label=f"basin {m.number}: ({m.x:.4g}, {m.y:.4g}), f = {m.f:.4g}") for m in minima]
    if (value == 0).any():
        handles.append(Patch(facecolor=BASIN_NONE, edgecolor="0.5", label="basin 0: rests in no minimum"))
    if table.keys == ("start.x", "start.y"):
        # (a map of the landscape's own square, in a figure to fit: at the top of the room the
        # layout gives it, under the title, its legend just below; the figure is cropped to them)
        ax.set_aspect("equal", anchor="N")
        ax.figure.set_size_inches(6.4, 7.4)
        for m in minima:
            ax.plot(m.x, m.y, "o", markersize=7, markerfacecolor=colours[m.number], markeredgecolor="k")
    return handles


def _contact_changes(table) -> bool:
    """Whether any run's contact changed mode (it slipped, gripped, landed or did not end
    rolling): only then are the contact's outcomes drawn against the varied key."""
    out = table.outcomes
    with np.errstate(invalid="ignore"):
        return bool(np.isfinite(out[:, [O_FIRST_SLIP, O_FIRST_GRIP]]).any() or (out[:, O_LANDINGS] > 0).any()
                    or ((out[:, O_END_MODE] != ROLLING) & np.isfinite(out[:, O_END_MODE])).any())


def _curves(plt, table, color):
    (key,) = table.keys
    x = table.grid.axes[0]
    order = np.argsort(x)
    contact, rested = _contact_changes(table), bool(np.isfinite(table.outcomes[:, O_REST_TIME]).any())
    shown = tuple(o for o in OUTCOMES if (contact or o not in CONTACT_OUTCOMES) and (rested or o not in REST_OUTCOMES))
    names = (color,) + tuple(o for o in shown if o != color)
    rows = math.ceil(len(names) / 4)
    fig, axes = plt.subplots(rows, 4, figsize=(12.0, 3.0 * rows), sharex=True)
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    codes = table.codes[order]
    for ax, name in zip(axes.ravel(), names):
        y = table[name][order]
        ax.plot(x[order], y, color="0.6", linewidth=0.8)
        for code, marker, colour, text in ((kernel.OK, ".", "C0", "ok"),
                                           (kernel.DOES_NOT_FIT, "x", "k", "does not fit"),
                                           (kernel.NONFINITE, "v", "#e7298a", "non-finite")):
            sel = codes == code
            if sel.any():
                ax.plot(x[order][sel], y[sel], marker, color=colour, markersize=4, linestyle="none",
                        label=text)
        ax.set_title(label(name), fontsize=9)
        if name == "energy_drift" and np.nanmax(np.abs(y), initial=0.0) > 0:
            ax.set_yscale("log")
        if name == "end_mode":
            ax.set_yticks(range(len(MODES)), MODES)
            ax.set_ylim(-0.5, len(MODES) - 0.5)
        ax.tick_params(labelsize=8)
    for ax in axes.ravel()[max(len(names) - 4, 0): len(names)]:   # (the lowest panel of each column)
        ax.set_xlabel(label(key), fontsize=9)
    if axes[0, 0].get_legend_handles_labels()[0]:  # none when no run was run (all refused)
        axes[0, 0].legend(fontsize=8)
    return fig
