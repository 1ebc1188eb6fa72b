"""The columns of a record file, format by format: delimited text (also gzipped), Parquet,
MAT (v5 and v7.3), WAV and TDMS, each read into a :class:`Table` of named columns with
the file's own metadata and sample rate, before a channel is chosen
(:mod:`pydiag.io.readers` chooses, converts and checks them). The table of what each
format is read with is :mod:`pydiag.io.readers`'s docstring.
"""

from __future__ import annotations

import csv
import gzip
import io
import json
import re
from pathlib import Path

import numpy as np

from pydiag.core.errors import MeasurementError

META_PREFIX = "# meta:"
#: The most samples a channel may hold: order tracking upsamples a record eightfold, so
#: this keeps one channel's analysis within about 2 GB (a record of 4 minutes at 66.7 kHz).
#: A longer record is refused before it is read whole, with the bound named: cut it.
MAX_SAMPLES = 16_000_000
RATE_VARIABLES = ("fs", "Fs", "FS", "sample_rate", "sample_rate_hz", "sampling_rate", "sr")
TEXT_SUFFIXES = (".csv", ".tsv", ".txt", ".dat")


class Table:
    """Columns as read, before a sample rate and a channel choice are applied."""

    def __init__(self, columns: dict[str, np.ndarray], metadata: dict | None = None,
                 rate_hz: float | None = None, rate_source: str | None = None) -> None:
        self.columns = columns
        self.metadata = metadata or {}
        self.rate_hz = rate_hz
        self.rate_source = rate_source


def fail(path: Path, message: str) -> MeasurementError:
    return MeasurementError(f"{path}: {message}")


def gzipped(path: Path) -> bool:
    return path.suffix.lower() == ".gz"


def _open_raw(path: Path):
    """The file's bytes, decompressed when it is gzipped."""
    return gzip.open(path, "rb") if gzipped(path) else open(path, "rb")


def _open_text(path: Path):
    return io.TextIOWrapper(_open_raw(path), encoding="utf-8-sig", newline="")


def _too_long(path: Path, n_samples: int) -> MeasurementError:
    return fail(path, f"{n_samples:,} samples a channel or more: pydiag reads at most "
                       f"{MAX_SAMPLES:,} (a record of {MAX_SAMPLES / 66_667 / 60:.0f} minutes at "
                       "66.7 kHz); cut the record into shorter ones")


def _check_text_rows(path: Path) -> None:
    """Count the lines without holding them (gzip streamed): refuse past MAX_SAMPLES."""
    lines = 0
    with _open_raw(path) as fh:
        while chunk := fh.read(1 << 22):
            lines += chunk.count(b"\n")
            if lines > MAX_SAMPLES + 100:  # a header and comments are not samples
                raise _too_long(path, lines)


def _first_lines(path: Path, n_lines: int = 50) -> list[str]:
    with _open_text(path) as fh:
        return [line for _, line in zip(range(n_lines), fh)]


def _is_number(token: str, decimal: str) -> bool:
    try:
        float(token.strip().replace(decimal, "."))
        return True
    except ValueError:
        return False


def read_text(path: Path) -> Table:
    import pandas as pd

    head = _first_lines(path)
    metadata, n_comments = {}, 0
    for line in head:
        if line.startswith(META_PREFIX):
            try:
                metadata = json.loads(line[len(META_PREFIX):])
            except json.JSONDecodeError as err:
                raise fail(path, f"bad metadata line: {err}") from err
        elif line.strip() and not line.startswith("#"):
            break
        n_comments += 1
    body = [line for line in head[n_comments:] if line.strip()]
    if not body:
        raise fail(path, "no data rows found")
    if not any(c in line for line in body[:20] for c in ",;\t") and \
            any(len(line.split()) > 1 for line in body[:20]):
        delimiter = " "  # whitespace-aligned (MATLAB's save -ascii: leading blanks, runs)
    else:
        try:
            delimiter = csv.Sniffer().sniff("".join(body[:20]), delimiters=",;\t ").delimiter
        except csv.Error:
            delimiter = ","  # one column
    sample = body[1] if len(body) > 1 else body[0]
    decimal = "," if delimiter in ";\t " and "," in sample and not _is_number(
        sample.split(delimiter)[0], ".") else "."
    first = [t.strip() for t in next(csv.reader([body[0].rstrip("\r\n")],
                                                delimiter=delimiter))
             if delimiter != " " or t.strip()]
    trailing = delimiter != " " and len(first) > 1 and first[-1] == "" and all(
        line.rstrip("\r\n").endswith(delimiter) for line in body[:20])
    if trailing:  # every line ends with the delimiter: no column after it
        first = first[:-1]
    has_header = not all(_is_number(t, decimal) for t in first)
    if has_header:
        duplicated = sorted({t for t in first if first.count(t) > 1})
        if duplicated:
            raise fail(path, f"duplicate column name(s) {', '.join(duplicated)}: which one is "
                              "the sensor? Rename them")
        names = first
    else:
        names = [f"ch{i + 1}" for i in range(len(first))]
    fast = decimal == "." and delimiter != " " and not trailing
    _check_text_rows(path)
    try:
        frame = pd.read_csv(path, sep=r"\s+" if delimiter == " " else delimiter,
                            skiprows=n_comments + (1 if has_header else 0), header=None,
                            names=names + ([""] if trailing else []), decimal=decimal,
                            engine="pyarrow" if fast else "c",
                            compression="gzip" if gzipped(path) else None,
                            encoding="utf-8-sig")
        if trailing:
            frame = frame.iloc[:, :-1]
    except (ValueError, pd.errors.ParserError, OSError, UnicodeDecodeError) as err:
        first_line = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise fail(path, f"cannot parse as {'decimal-comma ' if decimal == ',' else ''}text "
                          f"with delimiter {delimiter!r}: {first_line}") from err
    return Table(_numeric_columns(path, frame), metadata)


class Unusable(str):
    """Why a column cannot be a signal: an error only if the column is chosen (a label
    column or a channel at another rate beside the one asked for stops nothing)."""


def _numeric_columns(path: Path, frame) -> dict[str, np.ndarray | Unusable]:
    import pandas as pd

    columns: dict[str, np.ndarray | Unusable] = {}
    for name in frame.columns:
        col = frame[name]
        if not pd.api.types.is_numeric_dtype(col):
            values = pd.to_numeric(col, errors="coerce")
            bad = np.flatnonzero(values.isna() & col.notna())
            if bad.size:
                columns[str(name)] = Unusable(f"column '{name}' has a non-numeric value "
                                               f"({col.iloc[bad[0]]!r}, data row {bad[0] + 1})")
                continue
            col = values
        values = col.to_numpy(dtype=float, na_value=np.nan)
        missing = np.flatnonzero(np.isnan(values))
        if missing.size:
            columns[str(name)] = Unusable(
                f"column '{name}' has {missing.size} missing or NaN value(s), the first in "
                f"data row {missing[0] + 1}")
        elif not np.isfinite(values).all():
            columns[str(name)] = Unusable(f"column '{name}' has infinite values")
        else:
            columns[str(name)] = values
    return columns


def _read_parquet(path: Path) -> Table:
    import pandas as pd
    import pyarrow.parquet as pq

    try:
        rows = pq.ParquetFile(path).metadata.num_rows
    except Exception as err:  # noqa: BLE001
        raise fail(path, f"cannot read as Parquet: {err}") from err
    if rows > MAX_SAMPLES:
        raise _too_long(path, rows)
    try:
        frame = pd.read_parquet(path, engine="pyarrow")
        kv = pq.read_schema(path).metadata or {}
    except Exception as err:  # pyarrow raises its own kinds on a damaged file  # noqa: BLE001
        raise fail(path, f"cannot read as Parquet: {err}") from err
    metadata = json.loads(kv[b"pydiag"]) if b"pydiag" in kv else {}
    return Table(_numeric_columns(path, frame), metadata)


def _matrix_columns(name: str, value: np.ndarray, out: dict[str, np.ndarray]) -> None:
    a = np.asarray(value)
    if a.dtype.kind not in "fiu" or a.size < 2:
        return
    a = np.squeeze(a)
    if a.ndim == 1:
        out[name] = a.astype(float)
    elif a.ndim == 2:
        cols = a if a.shape[0] >= a.shape[1] else a.T  # samples along the longer axis
        for i in range(cols.shape[1]):
            out[f"{name}_{i + 1}"] = cols[:, i].astype(float)


def _hdf5_datasets(path: Path) -> dict[str, np.ndarray]:
    """Every dataset of a v7.3 MAT file (HDF5), a struct's fields named ``struct.field``
    (MATLAB's ``#refs#`` group of cell contents is not data of its own)."""
    import h5py

    items: dict[str, np.ndarray] = {}

    def visit(name: str, obj) -> None:
        if isinstance(obj, h5py.Dataset) and not name.startswith("#refs#"):
            if max(obj.shape, default=1) > MAX_SAMPLES:
                raise _too_long(path, max(obj.shape))
            items[name.replace("/", ".")] = np.asarray(obj)

    try:
        with h5py.File(path, "r") as f:
            f.visititems(visit)
    except OSError as err:
        raise fail(path, f"cannot read as a MATLAB v7.3 file: {err}") from err
    return items


def _read_mat(path: Path) -> Table:
    import warnings

    import scipy.io

    variables: dict[str, np.ndarray] = {}
    notes = []
    try:
        longest = max((max(shape, default=1) for _, shape, _ in scipy.io.whosmat(path)),
                      default=0)
        if longest > MAX_SAMPLES:
            raise _too_long(path, longest)
        with warnings.catch_warnings(record=True) as caught:  # said once, in our words
            warnings.simplefilter("always", scipy.io.matlab.MatReadWarning)
            raw = scipy.io.loadmat(path)
        twice = sorted({m.group(1) for w in caught
                        if (m := re.search(r"Duplicate variable name \"([^\"]*)\"",
                                           str(w.message)))})
        if twice:
            notes.append(f"variable(s) {', '.join(twice)} appear more than once in the file; "
                         "the last of each is read")
        items = {k: v for k, v in raw.items() if not k.startswith("__")}
    except NotImplementedError:  # v7.3 is HDF5
        items = _hdf5_datasets(path)
    except MeasurementError:
        raise
    except Exception as err:  # scipy raises several kinds on a non-MAT file  # noqa: BLE001
        raise fail(path, f"cannot read as a MATLAB file: {err}") from err
    rate = None
    for key in list(items):  # a struct's rate field (rec.fs) is the rate too
        if key.rsplit(".", 1)[-1] in RATE_VARIABLES and np.asarray(items[key]).size == 1:
            rate = float(np.asarray(items.pop(key)).ravel()[0])
            break
    for key, value in items.items():
        _matrix_columns(key, value, variables)
    return Table(variables, {"read_notes": notes} if notes else {}, rate,
                  "the file's rate variable" if rate else None)


def _read_wav(path: Path) -> Table:
    import warnings

    import scipy.io.wavfile

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", scipy.io.wavfile.WavFileWarning)
            rate, data = scipy.io.wavfile.read(path, mmap=True)
            if len(data) > MAX_SAMPLES:
                raise _too_long(path, len(data))
            data = np.array(data)
    except (ValueError, OSError, EOFError) as err:
        if "mmap length is greater than file size" in str(err):
            raise fail(path, "the WAV file is truncated: its header promises more samples "
                              "than it holds") from err
        raise fail(path, f"cannot read as WAV: {err}") from err
    for w in caught:
        if "EOF" in str(w.message):  # the header promises more than the file holds
            raise fail(path, f"the WAV file is truncated ({w.message}): its header promises "
                              "more samples than it holds")
    if data.dtype.kind in "iu":
        info = np.iinfo(data.dtype)
        data = (data.astype(float) - (info.max + 1 if data.dtype.kind == "u" else 0)) / (info.max + 1)
    data = np.asarray(data, dtype=float).reshape(len(data), -1)
    return Table({f"ch{i + 1}": data[:, i] for i in range(data.shape[1])}, {}, float(rate),
                  "the WAV header")


def _read_tdms(path: Path) -> Table:
    from nptdms import TdmsFile

    try:
        longest = max((len(c) for g in TdmsFile.read_metadata(path).groups()
                       for c in g.channels()), default=0)
    except Exception as err:  # noqa: BLE001
        raise fail(path, f"cannot read as TDMS: {err}") from err
    if longest > MAX_SAMPLES:
        raise _too_long(path, longest)
    try:
        tdms = TdmsFile.read(path)
    except Exception as err:  # npTDMS raises several kinds on a damaged file  # noqa: BLE001
        raise fail(path, f"cannot read as TDMS: {err}") from err
    found = [(g.name, c) for g in tdms.groups() for c in g.channels()]
    names = [c.name for _, c in found]
    columns, rates = {}, set()
    for group, channel in found:
        key = channel.name if names.count(channel.name) == 1 else f"{group}/{channel.name}"
        _matrix_columns(key, channel[:], columns)
        if "wf_increment" in channel.properties:
            rates.add(1.0 / float(channel.properties["wf_increment"]))
    if len(rates) > 1:
        raise fail(path, f"channels have different sample rates {sorted(rates)}")
    rate = rates.pop() if rates else None
    return Table(columns, {}, rate, "the TDMS wf_increment" if rate else None)


READERS = {".parquet": _read_parquet, ".mat": _read_mat, ".wav": _read_wav, ".tdms": _read_tdms}
