"""The figure of a track's residuals: per measured axis, the track minus the model against time,
with the noise's ±2σ band (docs/design.md §10)."""

from __future__ import annotations

import io
import textwrap
import warnings

from .track_check import Residuals


def figure_png(res: Residuals, title: str) -> bytes | None:
    """The residuals' figure as PNG bytes; None when matplotlib is missing. Matplotlib's own
    warnings do not reach the user."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        axes = res.track.axes
        fig, panels = plt.subplots(len(axes), 1, figsize=(8, 1.8 + 1.6 * len(axes)), sharex=True, squeeze=False)
        t, values, band = res.track.t, res.values * 1000, 2 * res.noise * 1000
        for k, (axis, panel) in enumerate(zip(axes, panels[:, 0])):
            panel.axhspan(-band, band, color="0.88", label=f"±2σ of the noise ({res.noise * 1000:.3g} mm)")
            panel.axhline(0.0, color="0.5", linewidth=0.8)
            panel.plot(t, values[:, k], ".", markersize=3, color="C0", label="track − model")
            panel.set_ylabel(f"{axis} (mm)")
        panels[0, 0].legend(loc="best", fontsize=8, framealpha=0.9)
        panels[-1, 0].set_xlabel("t (s)")
        fig.suptitle(f"{title}\n{textwrap.fill(res.verdict(), 110)}", fontsize=9, parse_math=False, usetex=False)
        fig.tight_layout()
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=110)
        plt.close(fig)
    return buffer.getvalue()
