"""The look every tool's figures share (matplotlib on the Agg backend) and the one way they are
saved: <stem>.png plus the other FORMATS, the PNG path returned, and the tagged points' positions
for report.html (hover.py)."""
from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # headless: make plots runs over ssh and in CI
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from analysis.common import hover  # noqa: E402

# --no-svg replaces it with ("png",): SVG is for papers and slides, and slower to write.
FORMATS = ("png", "svg")
MARKERS = "osD^v<>ph*"
LINE_STYLES = ("-", "--", "-.", ":")

plt.rcParams.update({"figure.dpi": 110, "savefig.dpi": 130, "axes.grid": True,
                     "grid.alpha": 0.3, "legend.fontsize": 8, "axes.titlesize": 11,
                     "svg.hashsalt": "particle-lab"})  # stable SVG ids: diffs show changes


def engine_styles(table) -> dict:
    """A line style per engine of `table` (in name order), so series of different engines differ
    in more than colour: a reader with a grey printout or colour blindness tells them apart."""
    if "engine" not in table:
        return {}
    engines = sorted(table["engine"].dropna().unique())
    return {e: LINE_STYLES[i % len(LINE_STYLES)] for i, e in enumerate(engines)}


def save(fig, stem: Path, layout: bool = True, formats: tuple[str, ...] | None = None) -> Path:
    """`formats`: instead of FORMATS (PNG is always written: reports embed it)."""
    stem.parent.mkdir(parents=True, exist_ok=True)
    for ax in fig.axes:
        widen_constant(ax)
    if layout:
        fig.tight_layout()
    for ext in dict.fromkeys(("png", *(formats or FORMATS))):
        fig.savefig(stem.with_suffix(f".{ext}"))
    hover.write_positions(fig, stem.with_suffix(".png"))  # after layout: where the points ended
    plt.close(fig)
    return stem.with_suffix(".png")


def widen_constant(ax) -> None:
    """A constant series on an autoscaled linear axis gets matplotlib's +-5% around its value:
    0.95-1.05 ticks that make rounding look like a trend. Show it from zero instead."""
    if ax.get_yscale() != "linear" or not ax.get_autoscaley_on():
        return
    low, high = ax.dataLim.y0, ax.dataLim.y1
    if not (np.isfinite(low) and np.isfinite(high)) or high - low > 1e-9 * max(abs(high), 1e-300):
        return
    ax.set_ylim(sorted((0.0, 2.0 * high)) if high != 0 else (-1.0, 1.0))


def readable_log(ax, axis: str) -> None:
    """Log scale labelled 1, 2, 5, 10, 20, ... in plain numbers: matplotlib's default labels
    only powers of ten, which leaves a one-decade axis with a single label. The axis label
    gains ", log scale": set the label first."""
    target = ax.yaxis if axis == "y" else ax.xaxis
    (ax.set_yscale if axis == "y" else ax.set_xscale)("log")
    label = target.get_label_text()
    if "log scale" not in label:  # the reader must know the spacing is not linear
        target.set_label_text(f"{label}, log scale" if label else "log scale")
    low, high = ax.get_ylim() if axis == "y" else ax.get_xlim()
    decades = math.log10(high / low) if low > 0 and high > low else 1
    # 1-2-5 ticks up to a few decades; beyond that they crowd, powers of ten suffice.
    subs = (1.0, 2.0, 5.0) if decades <= 2.5 else (1.0,)
    target.set_major_locator(matplotlib.ticker.LogLocator(subs=subs))
    target.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    target.set_minor_formatter(matplotlib.ticker.NullFormatter())
