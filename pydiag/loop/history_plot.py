"""The run history's error across model revisions, drawn (``pydiag history --plot``):
the error falling as physics is added to the model."""

from __future__ import annotations

from pathlib import Path

from pydiag.core.errors import OutputError
from pydiag.io.outputs import atomic_output

#: The formats :func:`plot` writes, by the file's suffix.
PLOT_FORMATS = (".png", ".svg", ".pdf")


def check_plot(out: str | Path) -> None:
    """OutputError unless ``out`` names a format :func:`plot` writes (before any work)."""
    if Path(out).suffix.lower() not in PLOT_FORMATS:
        raise OutputError(f"--plot {out}: the plot is written as {', '.join(PLOT_FORMATS)} "
                          "(by the file's suffix)")


def plot(rows: list[dict], out: str | Path, force: bool = False) -> Path:
    """Error per run, labelled with the model name: the error falling as physics is added.
    Written under the output policy (:mod:`pydiag.io.outputs`); the format follows the
    name's suffix (:data:`PLOT_FORMATS`)."""
    check_plot(out)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, ax = plt.subplots(figsize=(7, 3.5), dpi=110)
    ax.plot([r["id"] for r in rows], [r["error"] for r in rows], "o-", color="#1f5fa8")
    for r in rows:
        ax.annotate(r["model_name"] or Path(r["fmu"]).stem, (r["id"], r["error"]),
                    textcoords="offset points", xytext=(4, 6), fontsize=8)
    ax.set_xlabel("compare run")
    ax.set_ylabel("spectral error (Eq. 12, relative)")
    ax.set_ylim(bottom=0)
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.grid(alpha=0.3)
    fig.tight_layout()
    try:
        with atomic_output(out, force) as tmp:
            fig.savefig(tmp, format=Path(out).suffix.lower().lstrip("."))
    finally:
        plt.close(fig)
    return Path(out)
