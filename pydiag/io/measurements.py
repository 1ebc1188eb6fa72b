"""Write measurement records as CSV (reading, of every format: :mod:`pydiag.io.readers`).

CSV layout: a line ``# meta: {...}`` with JSON metadata (operating point, true parameters
of a simulated record, SNR, seed), a header row ``time_s,<channel>...``, numeric rows.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from pydiag.core.measurement import Measurement
from pydiag.io.outputs import atomic_output
from pydiag.io.formats import META_PREFIX
from pydiag.io.readers import TIME_COLUMNS

TIME_COLUMN = TIME_COLUMNS[0]


def write_measurement(path: str | Path, measurement: Measurement, overwrite: bool = False) -> None:
    """Write a CSV under the output policy (:mod:`pydiag.io.outputs`): an existing file is
    replaced only with ``overwrite``."""
    import pandas as pd  # here, as the readers do: importing it takes 0.25 s

    t = np.arange(measurement.n_samples) / measurement.sample_rate_hz
    with atomic_output(path, overwrite) as tmp, open(tmp, "w", newline="") as fh:
        fh.write(f"{META_PREFIX} {json.dumps(measurement.metadata, sort_keys=True)}\n")
        pd.DataFrame({TIME_COLUMN: t, **measurement.channels}).to_csv(fh, index=False)
