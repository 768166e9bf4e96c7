"""The benchmark's output: a Markdown report (tables) and a log-log figure (PNG)."""

from __future__ import annotations

import platform
from pathlib import Path

from .workprecision import Point


def machine() -> str:
    """The processor (from /proc/cpuinfo where there is one), core count and Python."""
    import os

    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores, {platform.system()}, Python {platform.python_version()}"


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
                     f"**{c['ratio']:.2f}×** ({c['ns_ours']:.0f} ns against {c['ns_c']:.0f} ns; "
                     f"after 1000 steps the two agree to {c['same_step']:.0e} m) | ≤ 1.2× |")
    lines += [
        f"| real time at h = 1e-4 | **{t['real_time']:.0f}×** | ≥ 300× |",
        f"| a formula never seen before, warm process (parse, derive, compile, validate, run) | "
        f"**{t['latency'] * 1e3:.0f} ms** | ≤ 100 ms |",
        f"| peak memory, 10⁷ steps recording every 100th | **{t['memory'] / 2**20:.0f} MB** | < 300 MB |",
        "", "Cold start (fresh processes):", "",
        "| | empty caches | caches on disk |", "|---|---|---|",
        f"| `import rollball` | {cold['import']:.2f} s | — |",
        f"| first simulate (compile or load the kernel) | {cold['first_simulate_cold_cache']:.2f} s | "
        f"{cold['first_simulate_disk_cache']:.2f} s |",
        f"| then a new formula / the same formula again | {cold['new_formula_cold_cache'] * 1e3:.0f} ms | "
        f"{cold['known_formula_disk_cache'] * 1e3:.0f} ms |",
        f"| whole process (interpreter, import, both runs) | {cold['process_cold_cache']:.2f} s | "
        f"{cold['process_disk_cache']:.2f} s |",
        "", "Cost of one step (hills, h = 1e-3):", "", "| method | ns per step |", "|---|---|",
    ]
    lines += [f"| {label} | {ns:.0f} |" for label, ns in t["costs"].items()]
    return lines


def _points(points: list[Point]) -> list[str]:
    lines = ["## Work against precision", "",
             "Error at the final time against scipy DOP853 at rtol = atol = 1e-12 on the same equations "
             "(max over x, y for α; over the entries for R); wall time is the median of the timed runs. "
             "Adaptive runs and scipy use atol = rtol · 1e-3.", ""]
    for scene in dict.fromkeys(p.scene for p in points):
        lines += [f"### {scene}", "", "| method | setting | steps | time (ms) | error α (m) | error R |",
                  "|---|---|---:|---:|---:|---:|"]
        lines += [f"| {p.label} | {p.setting} {p.value:.0e} | {p.steps} | {p.seconds * 1e3:.3g} | "
                  f"{p.error_alpha:.2e} | {p.error_R:.2e} |" for p in points if p.scene == scene]
        lines.append("")
    return lines


def markdown(targets: dict | None, points: list[Point], t_end: float | None, quick: bool) -> str:
    until = "each scene's duration" if t_end is None else f"t = {t_end:g} s"
    lines = ["# RollBall benchmark", "", f"Machine: {machine()}.", "",
             f"Mode: {'quick' if quick else 'full'}; scenes run to {until}.", ""]
    if targets is not None:
        lines += _targets(targets) + [""]
    lines += _points(points)
    return "\n".join(lines) + "\n"


def figure(points: list[Point], path: Path) -> bool:
    """Error in α against wall time, one panel per scene; False where matplotlib is missing."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    scenes = list(dict.fromkeys(p.scene for p in points))
    fig, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 4.6), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        for label in dict.fromkeys(p.label for p in points):
            line = [p for p in points if p.scene == scene and p.label == label]
            style = "k--o" if label.startswith("scipy") else ("-s" if "adaptive" in label else
                                                              ("-o" if "MK" in label else ":x"))
            ax.loglog([p.seconds for p in line], [max(p.error_alpha, 1e-16) for p in line], style,
                      label=label, markersize=4)
        ax.set_title(scene)
        ax.set_xlabel("wall time (s)")
        ax.grid(True, which="major", alpha=0.3)
    axes[0][0].set_ylabel("error in the contact point at t_end (m)")
    axes[0][-1].legend(fontsize=7)
    fig.suptitle(f"RollBall work-precision — {machine()}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True
