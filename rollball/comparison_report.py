"""A comparison's files: compare.json (docs/design.md §6), compare.md (the readable report) and
compare.png (error against wall time, and against step size with the fitted slopes).

This module reads what rollball.comparison measured; that module imports nothing from here."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import warnings

from .comparison import (ERROR_UNITS, ERRORS, FITTED, FLOOR_FACTOR, PLATEAU_SLOPE, REFERENCE_ACCURACY, SPREAD, TARGETS,
                         Comparison, RunResult, RunSpec, machine, setting_text)  # noqa: F401 - machine: bench and sweeps read it here
from .files import check_outputs, replace_together

FILES = ("compare.json", "compare.md", "compare.png")
KEPT_NAME = "compare-unsaved"   # where a report that could not replace the old one is kept
BELOW = "below the reference's accuracy"   # an error under the reference's floor: never quoted as a number


def literal(text: str) -> str:
    """User text as it can go into a UTF-8 file or a figure: a lone surrogate (which no
    encoding writes) becomes U+FFFD."""
    return "".join("\ufffd" if 0xD800 <= ord(c) <= 0xDFFF else c for c in str(text))


def _number(value: float | None, fmt: str = ".2e") -> str:
    return "—" if value is None or value != value else format(value, fmt)


def _scene_lines(cmp: Comparison) -> list[str]:
    s = cmp.scene
    lines = [f"- landscape: `z = {s.landscape}`"]
    lines += [f"- ball: radius {s.ball.radius:g} m, mass {s.ball.mass:g} kg; gravity {s.gravity:g} m/s²",
              f"- start: (x, y) = ({s.start.x:g}, {s.start.y:g}) m, (vx, vy) = ({s.start.vx:g}, "
              f"{s.start.vy:g}) m/s, spin {s.start.spin:g} rad/s",
              f"- compared up to t = {cmp.t_end:g} s at {round(cmp.t_end / cmp.record_dt) + 1} common times "
              f"(every {cmp.record_dt:.3g} s)"]
    return lines


def _table(cmp: Comparison, spec: RunSpec) -> list[str]:
    fixed = spec.fixed_step
    header = ("| dt (s) " if fixed else "| rtol ") + "| status | steps | rejected | evaluations | time (ms) | " \
        + " | ".join(f"{key} ({ERROR_UNITS[key]})" for key in ERRORS) + " |"
    lines = [header, "|" + "---|" * 5 + "---:|" * (1 + len(ERRORS))]
    for run in (r for r in cmp.runs if r.spec == spec):
        setting = f"{run.dt:.3g}" if fixed else f"{run.rtol:.0e}"
        mark = " *" if run.below_reference_floor else ""
        lines.append(f"| {setting}{mark} | {run.status} | {run.steps} | {run.rejected} | {run.evaluations} | "
                     f"{run.seconds * 1e3:.3g} | "
                     + " | ".join(BELOW if k in run.below else _number(run.error[k]) for k in ERRORS) + " |")
    stopped = [r for r in cmp.runs if r.spec == spec and not r.ok]
    if stopped:
        lines += ["", f"Stopped early: {stopped[-1].message}."]
    return lines


def findings(cmp: Comparison, heading: str = "##") -> list[str]:
    """The reference, the fastest runs and the fitted orders, as Markdown lines."""
    ref = cmp.reference
    checks = "; ".join(f"{c.method} at rtol {c.rtol:.0e}: " + ", ".join(f"{k} {_number(c.difference[k], '.1e')}"
                                                                       for k in ERRORS) for c in ref.checks)
    lines = [f"{heading} Reference", "",
             f"{ref.method} at rtol = {ref.rtol:.0e}, atol = {ref.atol:.0e} ({ref.steps} steps, "
             f"{ref.seconds * 1e3:.3g} ms). Its own error is estimated as the larger difference from two checks, "
             f"the same method a decade looser and another method at its tolerance ({checks}): "
             + ", ".join(f"{k} {_number(ref.error_estimates.get(k), '.1e')}" for k in ERRORS) + ". "
             f"Errors below the floor, the larger of {FLOOR_FACTOR:g}× the first difference (the looser run's error, "
             f"of the reference's order), the second (both runs' errors together) and round-off (100 ε times the "
             f"quantity's size), are not measured: "
             f"they read \"{BELOW}\", the run's setting is marked *, and they are left out of the fitted "
             f"orders: floors " + ", ".join(f"{k} {ref.floor(k):.1e}" for k in FITTED) + "."]
    lines += ["", f"**The reference is not checked to {REFERENCE_ACCURACY:.0e}**: {'; '.join(ref.problems)}. "
                  f"No error below its floor is quoted." if not ref.checked else
              f"The reference is checked: its own error is at most {REFERENCE_ACCURACY:.0e} in the contact point "
              f"(m) and the orientation."]
    if ref.status != "ok":
        lines += ["", f"The reference stopped early ({ref.message}): every run is compared up to "
                      f"t = {cmp.t_end:g} s."]
    lines += ["", f"{heading} Fastest runs", "",
              "Errors are maxima over the run at the common times; cost is compute time (processor "
              "time of the run, the median of repeats for short runs). Ranked by the larger of the contact-point (m) "
              "and orientation errors.", "", "| error at most | run | time (ms) | steps |", "|---|---|---:|---:|"]
    floor = max(ref.floor(key) for key in FITTED)
    for target in TARGETS:
        best = cmp.best(target)
        none = "none reached it" if floor <= target else f"below what the reference resolves ({floor:.1e})"
        lines.append(f"| {target:.0e} | {none} | — | — |" if best is None else
                     f"| {target:.0e} | {setting_text(best)} | {best.seconds * 1e3:.3g} | {best.steps} |")
    if cmp.orders:
        lines += ["", f"{heading} Orders", "",
                  f"Least-squares slope of log error against log dt over the runs that ended ok above the "
                  f"reference's floor, and of those over the asymptotic range: the finest neighbouring steps "
                  f"(at least three) whose pairwise slopes agree to within {SPREAD:g} (coarse steps whose "
                  f"error does not yet go as dt^order are left out). Where the error stops shrinking as the step "
                  f"does (pairwise slopes below {PLATEAU_SLOPE:g} at the finest steps), no order is fitted: "
                  f"the run is not converging there.",
                  "", "| run | contact point | orientation | expected |", "|---|---:|---:|---:|"]
        lines += [f"| {o.spec.label} | {_number(o.contact, '.2f')} | {_number(o.orientation, '.2f')} | "
                  f"{o.expected} |" for o in cmp.orders]
        notes = [f"- {o.spec.label}, {key}: not fitted: {reason}." for o in cmp.orders
                 for key, reason in o.reasons.items()]
        notes += [f"- {o.spec.label}, {key}: fitted {note}." for o in cmp.orders for key, note in o.notes.items()]
        lines += ["", *notes] if notes else []
    stalled = [f"- {spec.label}: {text}." for spec, _, text in cmp.not_converging if not spec.fixed_step]
    if stalled:
        lines += ["", f"{heading} Not converging", "", *stalled]
    return lines


def markdown(cmp: Comparison, figure: str | None = "compare.png") -> str:
    lines = ["# Speed against error", "", *([literal(cmp.scene.description), ""] if cmp.scene.description else []),
             *_scene_lines(cmp), "",
             f"Machine: {cmp.machine}. Mode: {'quick' if cmp.quick else 'full'}.", "", *findings(cmp)]
    if figure:
        lines += ["", f"![error against compute time and against step size]({figure})"]
    lines += ["", "## Runs"]
    for spec in cmp.specs:
        lines += ["", f"### {spec.label} (`{spec}`)", "", *_table(cmp, spec)]
    return "\n".join(lines) + "\n"


def style(spec: RunSpec, colors: dict) -> dict:
    """Line style of a run spec: a colour per method; solid Munthe-Kaas, dotted classic."""
    color = colors.setdefault(spec.method, f"C{len(colors) % 10}")
    if not spec.fixed_step:
        return dict(color=color, linestyle="-", marker="s")
    return dict(color=color, linestyle="-" if spec.munthe_kaas else ":", marker="o" if spec.munthe_kaas else "x")


def new_figure(width: float, height: float):
    """A matplotlib Figure drawn without a display (Agg)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def legend_below(fig, ax) -> None:
    """One legend for the figure's work-precision panels (ax: a panel that holds every line),
    below them, where it hides none of the lines."""
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 6), fontsize=7,
               title="solid: Munthe-Kaas, dotted: classic", title_fontsize=7)


def png(fig) -> bytes:
    out = io.BytesIO()
    fig.savefig(out, format="png", dpi=110)
    return out.getvalue()


def _measured(runs: list[RunResult], key: str, floor: float, x) -> tuple[list, list, list, list]:
    """The points (x, error) of runs whose error is measured, and of those below the floor
    drawn on it (open triangles: below the reference's accuracy, not a measured value)."""
    above = [r for r in runs if r.error[key] >= floor and r.error[key] > 0]
    below = [r for r in runs if not r.error[key] >= floor]
    return [x(r) for r in above], [r.error[key] for r in above], [x(r) for r in below], [floor] * len(below)


def spread_limits(ax, xs, ys) -> None:
    """Limits for a log-log panel whose points (``xs``, ``ys``: every one drawn) share one x or
    one y, or have none (a run too short to tell its settings apart, or an error at its floor
    everywhere): a decade either side, where matplotlib would widen them itself with a warning
    ("identical low and high xlims"). Other panels keep matplotlib's own limits."""
    for values, autoscale, limit in ((xs, ax.set_autoscalex_on, ax.set_xlim), (ys, ax.set_autoscaley_on, ax.set_ylim)):
        drawn = [v for v in values if v is not None and 0 < v < math.inf]
        if not drawn:
            continue
        low, high = min(drawn), max(drawn)
        if high <= low * (1 + 1e-9):
            autoscale(False)   # (first: setting a limit reads the other, autoscaled, which warns)
            limit(low / 10, high * 10)


def draw_work_precision(ax, cmp: Comparison, colors: dict) -> None:
    """Contact-point error against compute time, a line per run spec, the floor dashed; runs
    below the floor as open triangles on it."""
    floor = cmp.reference.floor("contact")
    xs, ys = [], [floor]
    for spec in cmp.specs:
        runs = [r for r in cmp.runs if r.spec == spec and r.ok]
        x, y, xb, yb = _measured(runs, "contact", floor, lambda r: r.seconds)
        xs += x + xb
        ys += y + yb
        line = style(spec, colors)
        ax.loglog(x, y, label=spec.label, markersize=4, **line)
        if xb:
            ax.loglog(xb, yb, linestyle="none", marker="v", markersize=5, markerfacecolor="none", color=line["color"])
    spread_limits(ax, xs, ys)
    ax.axhline(floor, color="0.6", linewidth=0.8, linestyle="--")
    ax.set(xlabel="compute time (s)", ylabel="contact-point error, max over the run (m)")
    ax.grid(True, which="major", alpha=0.3)


def draw_orders(ax, cmp: Comparison, colors: dict) -> None:
    """Orientation error against step size for the fixed-step specs, with the fitted slopes."""
    floor = cmp.reference.floor("orientation")
    xs, ys = [], [floor]
    for spec in (s for s in cmp.specs if s.fixed_step):
        runs = [r for r in cmp.runs if r.spec == spec and r.ok]
        x, y, xb, yb = _measured(runs, "orientation", floor, lambda r: r.dt)
        xs += x + xb
        ys += y + yb
        line = style(spec, colors)
        ax.loglog(x, y, markersize=4, **line)
        if xb:
            ax.loglog(xb, yb, linestyle="none", marker="v", markersize=5, markerfacecolor="none", color=line["color"])
        _slope_label(ax, cmp, spec, [r for r in runs if r.error["orientation"] >= floor], line["color"])
    spread_limits(ax, xs, ys)
    ax.set_ylim(top=10.0)  # a classic R far off SO(3) would squash the rest (‖R − R_ref‖_F ≤ 2√2 on it)
    ax.axhline(floor, color="0.6", linewidth=0.8, linestyle="--")
    ax.set(xlabel="step size dt (s)", ylabel="orientation error ‖R − R_ref‖_F, max over the run")
    ax.grid(True, which="major", alpha=0.3)


def figure(cmp: Comparison) -> bytes:
    """The PNG: contact-point error against compute time (every run spec), and orientation
    error against step size (fixed-step specs) with the fitted slopes written on the lines."""
    fig = new_figure(11, 5.4)
    left, right = fig.subplots(1, 2)
    colors: dict = {}
    draw_work_precision(left, cmp, colors)
    draw_orders(right, cmp, colors)
    left.set_title("error against time")
    right.set_title("error against step size (fitted slopes)")
    legend_below(fig, left)
    # the description is the user's text: drawn as written ($ is not mathtext, no TeX)
    ref = cmp.reference
    warning = "" if ref.checked else (f"\nREFERENCE NOT CHECKED to {REFERENCE_ACCURACY:.0e}: "
                                      f"{'; '.join(ref.problems)}; nothing below the dashed line is measured")
    fig.suptitle(f"{literal(cmp.scene.description or cmp.scene.landscape)} — to t = {cmp.t_end:g} s; dashed "
                 f"grey: the floor of the reference's own error (open triangles on it: {BELOW}){warning}\n"
                 f"{literal(cmp.machine)}",
                 fontsize=8, parse_math=False, usetex=False, color="black" if ref.checked else "firebrick")
    with warnings.catch_warnings():  # a glyph the font lacks is drawn as a box, not reported
        warnings.simplefilter("ignore")
        return png(fig)


def _slope_label(ax, cmp: Comparison, spec: RunSpec, runs: list[RunResult], color: str) -> None:
    order = next((o for o in cmp.orders if o.spec == spec), None)
    if order is not None and "orientation" in order.not_converging and runs:
        last = runs[-1]
        ax.annotate("not converging", (last.dt, last.error["orientation"]), color=color, fontsize=7,
                    xytext=(4, 4), textcoords="offset points")
        return
    if order is None or order.orientation is None or not runs:
        return
    middle = runs[len(runs) // 2]
    ax.annotate(f"{order.orientation:.2f}", (middle.dt, middle.error["orientation"]), color=color,
                fontsize=8, xytext=(6, -12) if spec.munthe_kaas else (-28, 6), textcoords="offset points",
                bbox=dict(boxstyle="round,pad=0.15", facecolor="white", edgecolor="none", alpha=0.8))


def render(cmp: Comparison) -> tuple[dict, list[str]]:
    """The report's files (name -> text or bytes; None for a figure that could not be drawn,
    so that an old one does not stay beside the new report) and notes on what is missing."""
    files = {"compare.json": json.dumps(cmp.to_dict(), indent=1, allow_nan=False) + "\n",
             "compare.md": markdown(cmp)}
    notes = []
    try:
        files["compare.png"] = figure(cmp)
    except Exception as error:  # noqa: BLE001 - the numbers are worth more than the picture
        files["compare.png"] = None
        notes.append(f"compare.png not drawn ({type(error).__name__}: {' '.join(str(error).split())[:200]})")
    return files, notes


def check(directory: Path, keep=()) -> None:
    """Before the first run: the folder and each file of the report may be written (OSError if not)."""
    check_outputs(directory, FILES, keep)


def save(cmp: Comparison, directory: str | Path, keep=()) -> list[Path]:
    """compare.json, compare.md and compare.png in ``directory`` (made if missing); ``keep``:
    paths not to overwrite (the scene). Render the three files, then replace them together (files.replace_together): all
    or none. ``NotReplaced`` when none was; the new files are then kept in a folder of their own
    (its name in the message). Returns the files written."""
    files, notes = render(cmp)
    written = replace_together(Path(directory), files, keep=keep, kept_name=KEPT_NAME)
    if notes:
        warnings.warn("; ".join(notes), stacklevel=2)
    return written
