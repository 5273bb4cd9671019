"""Log axes whose tick labels can be read: plain numbers, never two labels on top of each other.

Matplotlib's default log axis labels minor ticks in scientific notation when the data span about a
decade, and those labels collide. ``readable_log_axis`` labels ticks at 1, 2 and 5 x 10^k (1..9 x
10^k where the view spans less than half a decade, 10^k alone where it spans more than three), as
plain numbers (``%g``), leaves minor ticks unlabelled, draws the figure and then drops every other
label until no two labels' boxes overlap.
"""

from __future__ import annotations

import math


def _subs(low: float, high: float) -> tuple[float, ...]:
    decades = math.log10(high / low) if low > 0 and high > low else 0.0
    if decades < 0.5:
        return tuple(float(m) for m in range(1, 10))
    if decades <= 3:
        return (1.0, 2.0, 5.0)
    return (1.0,)


def overlapping_labels(ax, axis: str = "x") -> list[tuple[str, str]]:
    """Pairs of visible, non-empty tick labels of ``ax``'s ``axis`` whose drawn boxes overlap."""
    fig = ax.figure
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    target = ax.xaxis if axis == "x" else ax.yaxis
    low, high = sorted(target.get_view_interval())
    ticks = [t for t in target.get_major_ticks() + target.get_minor_ticks() if low <= t.get_loc() <= high]
    labels = [t.label1 for t in ticks if t.label1.get_visible()]
    shown = [(t.get_text(), t.get_window_extent(renderer)) for t in labels if t.get_text()]
    return [(a, b) for i, (a, box_a) in enumerate(shown) for b, box_b in shown[i + 1:] if box_a.overlaps(box_b)]


def readable_log_axis(ax, axis: str = "x") -> None:
    """Make ``ax``'s ``axis`` logarithmic with plain-number labels that do not overlap (see module doc)."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, LogLocator, NullFormatter

    target = ax.xaxis if axis == "x" else ax.yaxis
    (ax.set_xscale if axis == "x" else ax.set_yscale)("log")
    low, high = sorted(ax.get_xlim() if axis == "x" else ax.get_ylim())
    target.set_major_locator(LogLocator(base=10.0, subs=_subs(low, high), numticks=30))
    target.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
    target.set_minor_formatter(NullFormatter())
    (ax.set_xlim if axis == "x" else ax.set_ylim)(low, high)       # the locator must not widen the view
    ticks = [t for t in target.get_majorticklocs() if low <= t <= high]
    while len(ticks) > 1 and overlapping_labels(ax, axis):
        ticks = ticks[::2]
        target.set_major_locator(FixedLocator(ticks))
