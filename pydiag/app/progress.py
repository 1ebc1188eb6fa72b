"""Progress on stderr while a command works: the simulations of a fit, the records of a
batch (tqdm bars, none with --quiet)."""

from __future__ import annotations

import contextlib
import sys


def progress_bar(quiet: bool, desc: str = "diagnose"):
    """(update(done, total, best), close) for a tqdm bar on stderr; no-ops when quiet."""
    if quiet:
        return None, lambda: None
    from tqdm import tqdm
    bar = tqdm(total=1, desc=desc, unit="sim", file=sys.stderr, leave=False)

    def update(done: int, total: int, best: float) -> None:
        bar.total = total
        bar.n = done
        bar.set_postfix(best_error=f"{best:.4g}", refresh=False)
        bar.refresh()

    return update, bar.close


@contextlib.contextmanager
def records_bar(quiet: bool, total: int, desc: str):
    """update(done, total) of a tqdm bar of records on stderr; None when quiet."""
    if quiet:
        yield None
        return
    from tqdm import tqdm
    bar = tqdm(total=total, desc=desc, unit="meas", file=sys.stderr, leave=False)
    try:
        yield lambda done, total: bar.update(done - bar.n)
    finally:
        bar.close()
