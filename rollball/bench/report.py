"""The benchmark's output: a Markdown report (tables) and a log-log figure (PNG)."""

from __future__ import annotations

import math

from ..comparison_report import draw_work_precision, findings, legend_below, machine, new_figure, png
from ..run_size import MAX_ROWS
from .targets import DISSIPATION_GOAL, HYBRID_GOAL, LATENCY_GOAL, ROW_LIMIT_GOAL, SWEEP_GOAL
from .workprecision import SceneResult


def _missed(met: bool) -> str:
    """Said after a figure that misses its goal."""
    return "" if met else " — **missed**"


def _ratios(h: dict, suffix: str) -> str:
    """A hybrid sweep's two ratio cells: the median of the ratios and the ratio of the fastest
    sweeps (``ratio`` + suffix, ``fastest_ratio`` + suffix; "–" in a bench.json of before it),
    each marked where it misses the goal."""
    cells = []
    for key in ("ratio" + suffix, "fastest_ratio" + suffix):
        value = h.get(key)
        cells.append("–" if value is None else f"**{value:.1f}×**{_missed(value <= HYBRID_GOAL)}")
    return " | ".join(cells)


def _app_line(app: dict | None) -> str:
    label = ("| app responsiveness: longest gap of a 5 ms timer on the GUI thread while 10⁶ steps are "
             "computed and played (painting included) |")
    if not app or "error" in app:
        return f"{label} not measured ({(app or {}).get('error', 'not run')}) | ≤ 250 ms |"
    return (f"{label} **{app['longest_gap_ms']:.0f} ms**{_missed(app['longest_gap_ms'] <= 250)} "
            f"(median {app['median_gap_ms']:.0f} ms) | ≤ 250 ms |")


APP_LATENCY_GOAL_MS = 150   # an edit to the landscape drawn, the app's part
APP_TYPING_GOAL_MS = 50     # a key to the field painted while typing on (landscapes drawn meanwhile)


def _app_latency_lines(app: dict | None) -> list[str]:
    """The app's latency, from an edit of the landscape to its next frame on screen (measured
    by ``python -m rollball_app.responsiveness``, on the ripples example)."""
    latency = (app or {}).get("latency")
    if not latency:
        return []
    goal = f"≤ {APP_LATENCY_GOAL_MS} ms"
    rows = [("a parameter's slider moved (nothing compiled: "
             f"{latency['slider_compiles']} compiles)", latency["slider"]),
            ("a formula's last key, from the key, to a formula seen before (the app's part)", latency["formula_seen"]),
            ("the same to a formula never seen (checked and compiled in the background, applied when ready)",
             latency["formula_new"])]
    lines = [f"| app latency: {what}, to the landscape drawn (median of {latency['repeats']}) | "
             f"**{v['median_ms']:.0f} ms**{_missed(v['median_ms'] <= APP_LATENCY_GOAL_MS)} "
             f"(longest {v['longest_ms']:.0f} ms) | {goal} |" for what, v in rows] + [
             f"| the typing pause before a number's keystroke is applied, or a refused formula is marked (a valid "
             f"formula: none) | {latency['debounce_ms']} ms | — |"]
    repeats, keys = latency["repeats"], latency.get("typing_keys")
    told = [("a slider moved, to the path's preview drawn", latency.get("preview"), repeats, None),
            ("a key typed into the formula field, to the field painted", latency.get("keystroke"), repeats, None),
            ("the same while previews are computed back to back", latency.get("keystroke_previewing"), repeats, None),
            (f"the same while typing on, a key every {latency.get('typing_interval_ms')} ms, a term typed and deleted "
             f"({latency.get('typing_applied')} landscapes drawn meanwhile)", latency.get("keystroke_typing"), keys,
             APP_TYPING_GOAL_MS)]
    return lines + [f"| app latency: {what} (median of {count}) | {v['median_ms']:.0f} ms"
                    + ("" if goal is None else _missed(v["median_ms"] <= goal))
                    + f" (longest {v['longest_ms']:.0f} ms) | {'—' if goal is None else f'≤ {goal} ms'} |"
                    for what, v, count, goal in told if v]


def _targets(t: dict) -> list[str]:
    c, cold = t["c"], t["cold"]
    lines = ["## Speed targets", "",
             "RK4 Munthe-Kaas on the hills scene (0.5 sin x cos y, r = 0.1, m = 1, start (0.3, −0.2) at "
             "rest), with the validity checks of every run (fit, non-finite, normal force, lift-off) "
             "and every 100th step recorded.", "",
             "| target | measured | goal |", "|---|---|---|"]
    if c["ratio"] is None:
        lines.append(f"| one step against C | no gcc here: {c['ns_ours']:.0f} ns per step | ≤ 1.2× |")
    else:
        lines.append(f"| one step against C (gcc -O3 -march=native, same run, median of ratios) | "
                     f"**{c['ratio']:.2f}×**{_missed(c['ratio'] <= 1.2)} ({c['ns_ours']:.0f} ns against "
                     f"{c['ns_c']:.0f} ns; after 1000 steps the two agree to {c['same_step']:.0e} m) | ≤ 1.2× |")
    lines += [
        f"| real time at h = 1e-4 | **{t['real_time']:.0f}×**{_missed(t['real_time'] >= 300)} | ≥ 300× |",
        f"| new formula latency: a formula never seen before, warm process (parse, derive, compile, "
        f"validate, 100 steps; median) | **{t['latency'] * 1e3:.0f} ms**{_missed(t['latency'] <= LATENCY_GOAL)}"
        + (f" ({t['latency_cpu'] * 1e3:.0f} ms of CPU time)" if t.get("latency_cpu") is not None else "")
        + f" | ≤ {LATENCY_GOAL * 1e3:.0f} ms |",
        f"| peak memory, 10⁷ steps recording every 100th | **{t['memory'] / 2**20:.0f} MB**"
        f"{_missed(t['memory'] < 300 * 2**20)} | < 300 MB |",
        *([] if t.get("row_limit_memory") is None else [
            f"| peak memory, dopri5 recording every step of a run that may slip until the row limit "
            f"({MAX_ROWS:,} rows) stops it | **{t['row_limit_memory'] / 1e9:.2f} GB**"
            f"{_missed(t['row_limit_memory'] < ROW_LIMIT_GOAL)} | < {ROW_LIMIT_GOAL / 1e9:.1f} GB |"]),
        _app_line(t.get("app")),
        *_app_latency_lines(t.get("app")),
        f"| compiling every method in one process, empty caches (CPU time; once per machine, "
        f"`scripts/setup` does it; from the shipped kernel code) | **{cold['all_methods_cold_cache']:.1f} s**"
        f"{_missed(cold['all_methods_cold_cache'] <= 10)} | ≤ 10 s |",
        "", "Cold start (fresh processes):", "",
        "| | empty caches | caches on disk |", "|---|---|---|",
        f"| `import rollball` | {cold['import']:.2f} s | — |",
        f"| first simulate (compile or load the kernel) | {cold['first_simulate_cold_cache']:.2f} s | "
        f"{cold['first_simulate_disk_cache']:.2f} s |",
        f"| then a new formula / the same formula again | {cold['new_formula_cold_cache'] * 1e3:.0f} ms | "
        f"{cold['known_formula_disk_cache'] * 1e3:.0f} ms |",
        f"| whole process (interpreter, import, both runs) | {cold['process_cold_cache']:.2f} s | "
        f"{cold['process_disk_cache']:.2f} s |",
        *([] if cold.get("all_methods_numba_cold_cache") is None else [
            "", "Where the shipped kernel code does not fit this machine, numba compiles the kernel's sources "
                "(rollball/kernel/) instead: every method in one process with empty caches then took "
                f"{cold['all_methods_numba_cold_cache']:.1f} s of CPU time."]),
        "", "Cost of one step (hills, h = 1e-3):", "", "| method | ns per step |", "|---|---|",
    ]
    lines += [f"| {label} | {ns:.0f} |" for label, ns in t["costs"].items()]
    if t.get("hybrid"):
        lines += ["", "A run that changes mode against the same scene glued to its surface (CPU time per run, "
                      "medians, the two in turn; a flight in vacuum compiled, bounce after bounce: landing search, "
                      "rows and impacts; slips and grips in the kernel's runs, the other changes of mode in "
                      "Python):", "",
                  "| scene | changes mode | glued | ratio | goal |", "|---|---|---|---|---|"]
        lines += [f"| {name} | {h['hybrid_ms']:.1f} ms | {h['glued_ms']:.1f} ms | **{h['ratio']:.1f}×**"
                  f"{_missed(h['ratio'] <= HYBRID_GOAL)} | ≤ {HYBRID_GOAL:g}× |" for name, h in t["hybrid"].items()]
    sweeps = t.get("hybrid_sweeps")
    if sweeps:
        lines += ["", "A sweep of a scene that changes mode over its start speed (±5 %, one worker; the batch "
                      "loop rolls, flies, slips and grips its runs, leaving what it cannot finish to a `Simulation`) "
                      "against the "
                      "same sweep glued, CPU time, medians, the two in turn; and the ratio of the fastest sweeps:", "",
                  "| scene | runs | changes mode | glued | ratio | ratio of the fastest | goal |",
                  "|---|---|---|---|---|---|---|"]
        lines += [f"| {name} | {h['runs']} | {h['hybrid_s']:.2f} s | {h['glued_s']:.2f} s | "
                  f"{_ratios(h, '')} | ≤ {HYBRID_GOAL:g}× |" for name, h in sweeps.items()]
        every = [(name, h) for name, h in sweeps.items() if "ratio_all" in h]
        if every:
            lines += ["", f"The same sweeps on every core ({every[0][1]['workers']} workers, a sweep's default: "
                          "threads, as for the glued runs, where the batch loop runs them; worker processes for "
                          "runs through `Simulation`, which hold the interpreter's lock between their kernel calls, "
                          "where the sweep is large enough to repay starting them), wall time, medians, the two in "
                          "turn, the worker processes started by a sweep before (the first sweep, which would start "
                          "them, in its own column); and the ratio of the fastest sweeps:", "",
                      "| scene | changes mode | on | glued | ratio | ratio of the fastest | goal | first sweep |",
                      "|---|---|---|---|---|---|---|---|"]
            lines += [f"| {name} | {h['hybrid_all_s']:.2f} s | {'processes' if h.get('processes') else 'threads'} | "
                      f"{h['glued_all_s']:.2f} s | {_ratios(h, '_all')} | ≤ {HYBRID_GOAL:g}× | "
                      f"{h.get('hybrid_first_s', math.nan):.2f} s |" for name, h in every]
        dask = [(name, h) for name, h in sweeps.items() if "ratio_dask" in h]
        if dask:
            lines += ["", f"The same sweeps on a Dask cluster of {dask[0][1]['dask_workers']} worker processes on "
                          "this machine, wall time, medians, the two in turn; and the ratio of the fastest sweeps:", "",
                      "| scene | changes mode | glued | ratio | ratio of the fastest | goal |",
                      "|---|---|---|---|---|---|"]
            lines += [f"| {name} | {h['hybrid_dask_s']:.2f} s | {h['glued_dask_s']:.2f} s | {_ratios(h, '_dask')} | "
                      f"≤ {HYBRID_GOAL:g}× |" for name, h in dask]
    cost = t.get("dissipation")
    if cost:
        lines += ["", "The wells example to 16 s (rk4, dt 2e-3: 20 turning points) with rolling resistance, spin "
                      "friction and air, against the same run with none of them (CPU time per run, medians, the "
                      "two in turn; and the fastest run of each):", "",
                  "| with the three | without | ratio | fastest runs | ratio of the fastest | goal |",
                  "|---|---|---|---|---|---|",
                  f"| {cost['with_ms']:.1f} ms | {cost['without_ms']:.1f} ms | **{cost['ratio']:.2f}×**"
                  f"{_missed(cost['ratio'] <= DISSIPATION_GOAL)} | "
                  + (f"{cost['fastest_with_ms']:.1f} / {cost['fastest_without_ms']:.1f} ms | "
                     f"**{cost['fastest_ratio']:.2f}×**{_missed(cost['fastest_ratio'] <= DISSIPATION_GOAL)}"
                     if "fastest_ratio" in cost else "– | –")   # (a bench.json of before them)
                  + f" | ≤ {DISSIPATION_GOAL:g}× |"]
    sweep = t.get("sweep")
    if sweep:
        lines += ["", f"A sweep of {sweep['runs']} runs of the hills example over its start point (the compiled "
                      "batch path), wall time, one worker against two, the two in turn (medians):", "",
                  "| one worker | two workers | speed-up | goal |", "|---|---|---|---|",
                  f"| {sweep['one_s']:.2f} s | {sweep['two_s']:.2f} s | **{sweep['ratio']:.2f}×**"
                  f"{_missed(sweep['ratio'] >= SWEEP_GOAL)} | ≥ {SWEEP_GOAL:g}× |"]
    return lines


def _scene(result: SceneResult) -> list[str]:
    cmp = result.comparison
    lines = [f"### {result.name}", "", f"`z = {cmp.scene.landscape}`, to t = {cmp.t_end:g} s.", "",
             *findings(cmp, heading="####"), "", "#### scipy DOP853 on the same equations", "",
             "| rtol | evaluations | time (ms) | contact (m) | orientation |", "|---|---:|---:|---:|---:|"]
    lines += [f"| {b.rtol:.0e} | {b.evaluations} | {b.seconds * 1e3:.3g} | {b.contact:.2e} | "
              f"{b.orientation:.2e} |" for b in result.scipy]
    return lines + [""]


def markdown(targets: dict | None, results: list[SceneResult], t_end: float | None, quick: bool) -> str:
    until = "each scene's duration" if t_end is None else f"t = {t_end:g} s"
    lines = ["# RollBall benchmark", "", f"Machine: {machine()}.", "",
             f"Mode: {'quick' if quick else 'full'}; scenes run to {until}.", ""]
    if targets is not None:
        lines += _targets(targets) + [""]
    lines += ["## Work against precision", "",
              "`rollball compare` on each scene (every method over its ladder of steps or tolerances; "
              "the full tables are in bench.json), and scipy's DOP853 on the same equations "
              "(atol = 1e-3 rtol) against the same reference at the same times.", ""]
    for result in results:
        lines += _scene(result)
    return "\n".join(lines) + "\n"


def figure(results: list[SceneResult]) -> bytes:
    """Contact-point error against compute time, one panel per scene, scipy dashed black."""
    fig = new_figure(5.2 * len(results), 5.2)
    axes = fig.subplots(1, len(results), squeeze=False)[0]
    colors: dict = {}
    for ax, result in zip(axes, results):
        draw_work_precision(ax, result.comparison, colors)
        ax.loglog([b.seconds for b in result.scipy], [max(b.contact, 1e-16) for b in result.scipy], "k--o",
                  label="scipy DOP853", markersize=4)
        ax.set_title(result.name)
    legend_below(fig, axes[-1])
    fig.suptitle(f"RollBall work-precision — {machine()}", fontsize=9)
    return png(fig)
