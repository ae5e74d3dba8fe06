"""The figures' house style, applied explicitly (`styled` while drawing, `save_figure` while writing), and their
one writer: each file through data.provenance.atomic_path (a temporary sibling renamed into place, mode as open())."""
from __future__ import annotations

import functools
from pathlib import Path

import matplotlib.pyplot as plt

from ureterfsi.data.provenance import atomic_path

HOUSE_STYLE = {"font.size": 9, "axes.titlesize": 9, "legend.fontsize": 8, "axes.grid": True, "grid.alpha": 0.3,
               "figure.constrained_layout.use": True}


def styled(draw):
    """Decorator: `draw` makes its figure under HOUSE_STYLE."""
    @functools.wraps(draw)
    def wrapper(*args, **kwargs):
        with plt.rc_context(HOUSE_STYLE):
            return draw(*args, **kwargs)
    return wrapper


def save_figure(fig, paths, dpi: float = 150) -> None:
    """Write `fig` to every path (format from the extension), each atomically, then close it."""
    with plt.rc_context(HOUSE_STYLE):
        for p in paths:
            with atomic_path(p) as tmp:
                fig.savefig(tmp, dpi=dpi, format=Path(p).suffix.lstrip("."))
    plt.close(fig)


def figure_paths(stem, formats) -> list[str]:
    """stem.<ext> for every format."""
    return [f"{stem}.{ext}" for ext in formats]
