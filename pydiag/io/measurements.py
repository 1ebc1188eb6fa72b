"""Measurement files: read and write records as CSV.

CSV layout: optional comment lines starting with ``#``; a line ``# meta: {...}`` holds
JSON metadata (operating point, true parameters of a simulated record, SNR, seed).
Then a header row and numeric rows. A ``time_s`` column gives the sample rate;
without one, the sample rate must be given.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from pydiag.core.errors import MeasurementError
from pydiag.core.measurement import Measurement
from pydiag.io.outputs import atomic_output

TIME_COLUMN = "time_s"
META_PREFIX = "# meta:"


def write_measurement(path: str | Path, measurement: Measurement, overwrite: bool = False) -> None:
    """Write a CSV under the output policy (:mod:`pydiag.io.outputs`): an existing file is
    replaced only with ``overwrite``."""
    t = np.arange(measurement.n_samples) / measurement.sample_rate_hz
    with atomic_output(path, overwrite) as tmp, open(tmp, "w", newline="") as fh:
        fh.write(f"{META_PREFIX} {json.dumps(measurement.metadata, sort_keys=True)}\n")
        writer = csv.writer(fh)
        writer.writerow([TIME_COLUMN, *measurement.channels])
        cols = np.column_stack([t, *measurement.channels.values()])
        for row in cols:
            writer.writerow([repr(float(v)) for v in row])


def read_measurement(path: str | Path, sample_rate_hz: float | None = None,
                     columns: list[str] | None = None) -> Measurement:
    """Read a CSV measurement; every problem raises MeasurementError with one clear line."""
    path = Path(path)
    try:
        lines = path.read_text().splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise MeasurementError(f"cannot read {path}: {getattr(err, 'strerror', None) or err}") from err
    metadata: dict = {}
    body = []
    for line in lines:
        if line.startswith(META_PREFIX):
            try:
                metadata = json.loads(line[len(META_PREFIX):])
            except json.JSONDecodeError as err:
                raise MeasurementError(f"{path}: bad metadata line: {err}") from err
        elif line.startswith("#") or not line.strip():
            continue
        else:
            body.append(line)
    if len(body) < 2:
        raise MeasurementError(f"{path}: no header and data rows found")
    header = [h.strip() for h in next(csv.reader([body[0]]))]
    try:
        data = np.array([[float(v) for v in row] for row in csv.reader(body[1:])], dtype=float)
    except ValueError as err:
        raise MeasurementError(f"{path}: non-numeric value in the data ({err})") from err
    if data.ndim != 2 or data.shape[1] != len(header):
        raise MeasurementError(f"{path}: rows do not all have {len(header)} values")
    if np.isnan(data).any():
        col = header[int(np.where(np.isnan(data))[1][0])]
        raise MeasurementError(f"{path}: column '{col}' contains NaN values")
    if not np.isfinite(data).all():
        raise MeasurementError(f"{path}: the data contain infinite values")
    table = dict(zip(header, data.T))
    if TIME_COLUMN in table:
        t = table.pop(TIME_COLUMN)
        dt = np.diff(t)
        if dt.size < 1 or np.any(dt <= 0):
            raise MeasurementError(f"{path}: '{TIME_COLUMN}' must increase strictly")
        if np.ptp(dt) > 1e-6 * np.mean(dt):
            raise MeasurementError(f"{path}: '{TIME_COLUMN}' is not uniformly sampled")
        rate = 1.0 / float(np.mean(dt))
        if sample_rate_hz is not None and abs(rate - sample_rate_hz) > 1e-6 * rate:
            raise MeasurementError(f"{path}: --sample-rate {sample_rate_hz} Hz disagrees with the "
                                   f"time column ({rate:.6g} Hz)")
        sample_rate_hz = rate
    elif sample_rate_hz is None:
        raise MeasurementError(f"{path}: no '{TIME_COLUMN}' column; give --sample-rate")
    if not table:
        raise MeasurementError(f"{path}: no signal column")
    measurement = Measurement(table, float(sample_rate_hz), metadata)
    return measurement.select(columns) if columns else measurement
