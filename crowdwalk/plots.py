"""Report plots (matplotlib, imported lazily, Agg backend): one function per figure.

Each function takes arrays or result objects, writes a PNG and returns its path.
"""

from __future__ import annotations

from pathlib import Path


def _pyplot():
    """Import matplotlib's pyplot with a file-only backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, out: str | Path) -> Path:
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120, bbox_inches="tight")
    _pyplot().close(fig)
    return out
