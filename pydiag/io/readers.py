"""Read a measurement from the files engineers have, picked by extension.

One concern: a record file in, a :class:`~pydiag.core.measurement.Measurement` out, with
every way a real file goes wrong refused in one line that names it.

=================  ==========================================================================
extension          how
=================  ==========================================================================
.csv .tsv .txt     pandas with the pyarrow engine; delimiter sniffed (``,`` ``;`` tab space;
.dat (+ .gz)       whitespace-aligned columns with leading blanks as MATLAB's ``save -ascii``
                   writes them), a delimiter ending every line ignored, decimal comma accepted
                   with ``;`` or tab, header optional (columns are then ``ch1``, ``ch2``...),
                   leading ``#`` lines skipped, ``# meta: {json}`` kept
.parquet           pandas/pyarrow; the file's ``pydiag`` key-value metadata kept
.mat               MATLAB v5 (scipy.io) or v7.3 (h5py): every numeric vector is a channel
                   (a matrix gives ``NAME_1``, ``NAME_2``... per column)
.wav               scipy.io.wavfile: channels ``ch1``...; integer PCM scaled to full scale 1
.tdms              npTDMS: channels named ``group/channel`` (or ``channel`` when unique)
.zip               one record file of the formats above inside (as data sets ship them)
=================  ==========================================================================

The sample rate comes from, in this order: a time column (``time_s``, ``time``, ``t``;
accepted when every sample lies within 1 % of a sample interval of a uniform grid), the
file itself (WAV rate, TDMS ``wf_increment``, a scalar ``fs``/``sample_rate`` variable
of a MAT file), or ``sample_rate_hz``. Given as well, it must agree with the file to 0.1 %.
The source is kept in ``metadata["sample_rate_source"]``.

Channels are chosen and mapped to model outputs with specs ``NAME=OUTPUT`` (``NAME`` alone
keeps the name), and converted to SI with ``units`` (:mod:`pydiag.io.units`); a column
not chosen is not checked (a label column, a channel at another rate). A chosen
channel that is constant (a dead sensor), a duplicated column name, a missing or non-numeric
value, and a value more than ``MAX_SPIKE`` times the channel's median absolute deviation
from its median (a corrupt value or a DAQ's overflow code such as 9.9e37; the sharpest
impacts of a broken tooth stand some tens of times above it) are refused with one line
naming the file and the column.
"""

from __future__ import annotations

import csv
import gzip
import io
import json
import re
import shutil
from pathlib import Path

import numpy as np

from pydiag.core.errors import MeasurementError, PydiagError, UsageError
from pydiag.core.measurement import Measurement
from pydiag.io.units import is_voltage, sensitivity_factor, si_factor

TIME_COLUMNS = ("time_s", "time", "t")
META_PREFIX = "# meta:"
#: A time column is uniform when every sample lies this close to the grid, in samples.
TIME_TOLERANCE = 0.01
#: A given sample rate must agree with the file's this closely (relative).
RATE_TOLERANCE = 1e-3
#: A sample this many times the channel's median absolute deviation from its median is refused.
MAX_SPIKE = 1e6
#: The most samples a channel may hold: order tracking upsamples a record eightfold, so
#: this keeps one channel's analysis within about 2 GB (a record of 4 minutes at 66.7 kHz).
#: A longer record is refused before it is read whole, with the bound named: cut it.
MAX_SAMPLES = 16_000_000
RATE_VARIABLES = ("fs", "Fs", "FS", "sample_rate", "sample_rate_hz", "sampling_rate", "sr")
TEXT_SUFFIXES = (".csv", ".tsv", ".txt", ".dat")
SUFFIXES = TEXT_SUFFIXES + (".parquet", ".mat", ".wav", ".tdms", ".zip")
#: The largest record a zip may hold, bytes uncompressed (a 4 s record of three channels
#: at 66.7 kHz as text is 13 MB).
MAX_ZIPPED_BYTES = 2 * 1024 ** 3


class _Table:
    """Columns as read, before a sample rate and a channel choice are applied."""

    def __init__(self, columns: dict[str, np.ndarray], metadata: dict | None = None,
                 rate_hz: float | None = None, rate_source: str | None = None) -> None:
        self.columns = columns
        self.metadata = metadata or {}
        self.rate_hz = rate_hz
        self.rate_source = rate_source


def _fail(path: Path, message: str) -> MeasurementError:
    return MeasurementError(f"{path}: {message}")


def _gzipped(path: Path) -> bool:
    return path.suffix.lower() == ".gz"


def _open_raw(path: Path):
    """The file's bytes, decompressed when it is gzipped."""
    return gzip.open(path, "rb") if _gzipped(path) else open(path, "rb")


def _open_text(path: Path):
    return io.TextIOWrapper(_open_raw(path), encoding="utf-8-sig", newline="")


def _too_long(path: Path, n_samples: int) -> MeasurementError:
    return _fail(path, f"{n_samples:,} samples a channel or more: pydiag reads at most "
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


def _head(path: Path, n_lines: int = 50) -> list[str]:
    with _open_text(path) as fh:
        return [line for _, line in zip(range(n_lines), fh)]


def _is_number(token: str, decimal: str) -> bool:
    try:
        float(token.strip().replace(decimal, "."))
        return True
    except ValueError:
        return False


def _read_text(path: Path) -> _Table:
    import pandas as pd

    head = _head(path)
    metadata, n_comments = {}, 0
    for line in head:
        if line.startswith(META_PREFIX):
            try:
                metadata = json.loads(line[len(META_PREFIX):])
            except json.JSONDecodeError as err:
                raise _fail(path, f"bad metadata line: {err}") from err
        elif line.strip() and not line.startswith("#"):
            break
        n_comments += 1
    body = [line for line in head[n_comments:] if line.strip()]
    if not body:
        raise _fail(path, "no data rows found")
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
            raise _fail(path, f"duplicate column name(s) {', '.join(duplicated)}: which one is "
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
                            compression="gzip" if _gzipped(path) else None,
                            encoding="utf-8-sig")
        if trailing:
            frame = frame.iloc[:, :-1]
    except (ValueError, pd.errors.ParserError, OSError, UnicodeDecodeError) as err:
        first_line = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise _fail(path, f"cannot parse as {'decimal-comma ' if decimal == ',' else ''}text "
                          f"with delimiter {delimiter!r}: {first_line}") from err
    return _Table(_numeric_columns(path, frame), metadata)


class _Unusable(str):
    """Why a column cannot be a signal: an error only if the column is chosen (a label
    column or a channel at another rate beside the one asked for stops nothing)."""


def _numeric_columns(path: Path, frame) -> dict[str, np.ndarray | _Unusable]:
    import pandas as pd

    columns: dict[str, np.ndarray | _Unusable] = {}
    for name in frame.columns:
        col = frame[name]
        if not pd.api.types.is_numeric_dtype(col):
            values = pd.to_numeric(col, errors="coerce")
            bad = np.flatnonzero(values.isna() & col.notna())
            if bad.size:
                columns[str(name)] = _Unusable(f"column '{name}' has a non-numeric value "
                                               f"({col.iloc[bad[0]]!r}, data row {bad[0] + 1})")
                continue
            col = values
        values = col.to_numpy(dtype=float, na_value=np.nan)
        missing = np.flatnonzero(np.isnan(values))
        if missing.size:
            columns[str(name)] = _Unusable(
                f"column '{name}' has {missing.size} missing or NaN value(s), the first in "
                f"data row {missing[0] + 1}")
        elif not np.isfinite(values).all():
            columns[str(name)] = _Unusable(f"column '{name}' has infinite values")
        else:
            columns[str(name)] = values
    return columns


def _read_parquet(path: Path) -> _Table:
    import pandas as pd
    import pyarrow.parquet as pq

    try:
        rows = pq.ParquetFile(path).metadata.num_rows
    except Exception as err:  # noqa: BLE001
        raise _fail(path, f"cannot read as Parquet: {err}") from err
    if rows > MAX_SAMPLES:
        raise _too_long(path, rows)
    try:
        frame = pd.read_parquet(path, engine="pyarrow")
        kv = pq.read_schema(path).metadata or {}
    except Exception as err:  # pyarrow raises its own kinds on a damaged file  # noqa: BLE001
        raise _fail(path, f"cannot read as Parquet: {err}") from err
    metadata = json.loads(kv[b"pydiag"]) if b"pydiag" in kv else {}
    return _Table(_numeric_columns(path, frame), metadata)


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
        raise _fail(path, f"cannot read as a MATLAB v7.3 file: {err}") from err
    return items


def _read_mat(path: Path) -> _Table:
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
        raise _fail(path, f"cannot read as a MATLAB file: {err}") from err
    rate = None
    for key in list(items):  # a struct's rate field (rec.fs) is the rate too
        if key.rsplit(".", 1)[-1] in RATE_VARIABLES and np.asarray(items[key]).size == 1:
            rate = float(np.asarray(items.pop(key)).ravel()[0])
            break
    for key, value in items.items():
        _matrix_columns(key, value, variables)
    return _Table(variables, {"read_notes": notes} if notes else {}, rate,
                  "the file's rate variable" if rate else None)


def _read_wav(path: Path) -> _Table:
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
            raise _fail(path, "the WAV file is truncated: its header promises more samples "
                              "than it holds") from err
        raise _fail(path, f"cannot read as WAV: {err}") from err
    for w in caught:
        if "EOF" in str(w.message):  # the header promises more than the file holds
            raise _fail(path, f"the WAV file is truncated ({w.message}): its header promises "
                              "more samples than it holds")
    if data.dtype.kind in "iu":
        info = np.iinfo(data.dtype)
        data = (data.astype(float) - (info.max + 1 if data.dtype.kind == "u" else 0)) / (info.max + 1)
    data = np.asarray(data, dtype=float).reshape(len(data), -1)
    return _Table({f"ch{i + 1}": data[:, i] for i in range(data.shape[1])}, {}, float(rate),
                  "the WAV header")


def _read_tdms(path: Path) -> _Table:
    from nptdms import TdmsFile

    try:
        longest = max((len(c) for g in TdmsFile.read_metadata(path).groups()
                       for c in g.channels()), default=0)
    except Exception as err:  # noqa: BLE001
        raise _fail(path, f"cannot read as TDMS: {err}") from err
    if longest > MAX_SAMPLES:
        raise _too_long(path, longest)
    try:
        tdms = TdmsFile.read(path)
    except Exception as err:  # npTDMS raises several kinds on a damaged file  # noqa: BLE001
        raise _fail(path, f"cannot read as TDMS: {err}") from err
    found = [(g.name, c) for g in tdms.groups() for c in g.channels()]
    names = [c.name for _, c in found]
    columns, rates = {}, set()
    for group, channel in found:
        key = channel.name if names.count(channel.name) == 1 else f"{group}/{channel.name}"
        _matrix_columns(key, channel[:], columns)
        if "wf_increment" in channel.properties:
            rates.add(1.0 / float(channel.properties["wf_increment"]))
    if len(rates) > 1:
        raise _fail(path, f"channels have different sample rates {sorted(rates)}")
    rate = rates.pop() if rates else None
    return _Table(columns, {}, rate, "the TDMS wf_increment" if rate else None)


READERS = {".parquet": _read_parquet, ".mat": _read_mat, ".wav": _read_wav, ".tdms": _read_tdms}


def _read_zipped(path: Path, sample_rate_hz: float | None, channels: list[str] | None,
                 units, sensitivities: dict[str, str] | None) -> Measurement:
    """The one record a zip holds (as data sets ship them), read as its own format."""
    import tempfile
    import zipfile

    try:
        with zipfile.ZipFile(path) as archive:
            members = [m for m in archive.infolist() if not m.is_dir()
                       and not Path(m.filename).name.startswith(".")
                       and not m.filename.startswith("__MACOSX/")]
            if len(members) != 1:
                raise _fail(path, f"a zip must hold one record file, it holds {len(members)}"
                                  + (f": {', '.join(m.filename for m in members[:5])}"
                                     if members else ""))
            member = members[0]
            name = Path(member.filename).name
            if _suffix(Path(name)) not in SUFFIXES or _suffix(Path(name)) == ".zip":
                raise _fail(path, f"its record {name} is of no format pydiag reads")
            if member.file_size > MAX_ZIPPED_BYTES:
                raise _fail(path, f"its record {name} is {member.file_size / 1e9:.1f} GB "
                                  f"unpacked, over the {MAX_ZIPPED_BYTES / 1e9:.1f} GB pydiag "
                                  "reads from a zip: unpack it first")
            with tempfile.TemporaryDirectory(prefix="pydiag_zip_") as tmp:
                inner = Path(tmp) / name
                with archive.open(member) as src, open(inner, "wb") as dst:
                    shutil.copyfileobj(src, dst, 1 << 20)
                try:
                    m = read_measurement(inner, sample_rate_hz, channels, units,
                                         sensitivities)
                except PydiagError as err:  # named as the user knows it, not our copy
                    raise type(err)(str(err).replace(str(inner),
                                                     f"{path}:{member.filename}")) from err
    except (zipfile.BadZipFile, OSError) as err:
        raise _fail(path, f"cannot read the zip: {err}") from err
    return Measurement(m.channels, m.sample_rate_hz,
                       {**m.metadata, "file": f"{path}:{member.filename}"})


def _usable(path: Path, column: np.ndarray | _Unusable) -> np.ndarray:
    if isinstance(column, _Unusable):
        raise _fail(path, str(column))
    return column


def _suffix(path: Path) -> str:
    suffixes = [s.lower() for s in path.suffixes]
    return suffixes[-2] if suffixes[-1:] == [".gz"] and len(suffixes) > 1 else (suffixes or [""])[-1]


def _check_spikes(path: Path, name: str, values: np.ndarray) -> None:
    deviation = np.abs(values - np.median(values))
    mad = float(np.median(deviation))
    worst = int(np.argmax(deviation))
    moving = int(np.count_nonzero(deviation)) if mad == 0 else values.size
    if 0 < moving < 3:  # one value but for a glitch or two: no signal, and no tacho either
        raise _fail(path, f"channel '{name}' holds one value ({np.median(values):g}) in all but "
                          f"{moving} of its {values.size} samples: a dead sensor with glitches?")
    if mad > 0 and deviation[worst] > MAX_SPIKE * mad:
        raise _fail(path, f"channel '{name}' sample {worst} is {values[worst]:g}, "
                          f"{deviation[worst] / mad:.2g} times the channel's median deviation: "
                          "a corrupt value or an overflow code?")


def is_measurement_file(path: str | Path) -> bool:
    """Whether the name has an extension pydiag reads."""
    return _suffix(Path(path)) in SUFFIXES


def _time_rate(path: Path, name: str, t: np.ndarray) -> float:
    """The rate of a uniform time column; MeasurementError otherwise."""
    if t.size < 2:
        raise _fail(path, "one row only: a record needs at least two samples")
    if np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise _fail(path, f"'{name}' must increase strictly (data rows {k + 1} and {k + 2})")
    dt = (t[-1] - t[0]) / (t.size - 1)
    deviation = float(np.max(np.abs(t - (t[0] + dt * np.arange(t.size))))) / dt
    if deviation > TIME_TOLERANCE:
        raise _fail(path, f"'{name}' is not uniformly sampled: a sample lies {deviation:.3g} "
                          f"sample intervals off the uniform grid (tolerance {TIME_TOLERANCE:g})")
    return 1.0 / dt


def parse_channel(spec: str) -> tuple[str, str]:
    """``NAME=OUTPUT`` -> (NAME, OUTPUT); ``NAME`` -> (NAME, NAME)."""
    name, sep, output = spec.partition("=")
    name, output = name.strip(), output.strip()
    if not name or (sep and not output):
        raise UsageError(f"a channel is NAME or NAME=OUTPUT, got '{spec}'")
    return name, output or name


def parse_units(specs: list[str] | None) -> dict[str | None, str]:
    """``UNIT`` (every channel) or ``NAME=UNIT`` -> {NAME or None: UNIT}."""
    units: dict[str | None, str] = {}
    for spec in specs or []:
        name, sep, unit = spec.rpartition("=") if "=" in spec else ("", "", spec)
        if (sep and not name.strip()) or not unit.strip():
            raise UsageError(f"a unit is UNIT or NAME=UNIT, got '{spec}'")
        units[name.strip() or None] = unit.strip()
    return units


def read_measurement(path: str | Path, sample_rate_hz: float | None = None,
                     channels: list[str] | None = None,
                     units: list[str] | dict[str | None, str] | None = None,
                     sensitivities: dict[str, str] | None = None) -> Measurement:
    """Read a measurement file (see the module docstring for the formats).

    Args:
        path: the file; its format from the extension (``.gz`` compressed text too)
        sample_rate_hz: the rate, when the file has none (checked against it otherwise)
        channels: ``NAME`` or ``NAME=OUTPUT`` specs (default: every column but time)
        units: ``UNIT`` for every channel or ``NAME=UNIT`` (NAME as in the file or as
            mapped); values are converted to SI. A voltage (V, mV) without a sensitivity
            is kept in volts: the level is not known, and a fit takes it as a gain
        sensitivities: NAME -> a sensor's sensitivity (``100 mV/g``): the channel, in
            volts unless its unit says another voltage, is converted to SI through it

    Returns a Measurement whose channels carry the OUTPUT names, in SI units when a unit
    was given, and metadata: ``file``, ``sample_rate_source``, ``channel_map``, ``units``
    (as given, in words), ``si_units`` (output -> the SI unit it is now in) and
    ``unknown_level`` (the outputs kept in volts: their level is not known).
    Every problem with the file raises MeasurementError naming it; a bad spec UsageError.
    """
    path = Path(path)
    suffix = _suffix(path)
    if suffix not in SUFFIXES:
        raise _fail(path, f"unknown measurement format '{suffix or path.name}'; pydiag reads "
                          f"{', '.join(SUFFIXES)} (text also gzipped)")
    if _gzipped(path) and suffix not in TEXT_SUFFIXES:
        raise _fail(path, f"only text records can be gzipped, not '{suffix}'")
    if not path.is_file():
        raise _fail(path, "cannot read: no such file" if not path.exists() else
                    "cannot read: not a regular file")
    if suffix == ".zip":
        return _read_zipped(path, sample_rate_hz, channels, units, sensitivities)
    try:
        table = (_read_text if suffix in TEXT_SUFFIXES else READERS[suffix])(path)
    except (OSError, EOFError, UnicodeDecodeError, gzip.BadGzipFile) as err:
        raise _fail(path, f"cannot read: {getattr(err, 'strerror', None) or err}") from err
    columns = dict(table.columns)
    rate, source = table.rate_hz, table.rate_source
    time_name = next((c for c in columns if c.lower() in TIME_COLUMNS), None)
    if time_name is not None:
        rate, source = _time_rate(path, time_name, _usable(path, columns.pop(time_name))), \
            f"column '{time_name}'"
    if rate is not None and sample_rate_hz is not None:
        if abs(rate - sample_rate_hz) > RATE_TOLERANCE * rate:
            raise _fail(path, f"--sample-rate {sample_rate_hz:g} Hz disagrees with {source} "
                              f"({rate:.8g} Hz)")
    elif rate is None:
        if sample_rate_hz is None:
            raise _fail(path, "the file has no time column or sample rate; give --sample-rate")
        rate, source = float(sample_rate_hz), "--sample-rate"
    if not columns:
        raise _fail(path, "no signal column")
    specs = [parse_channel(s) for s in channels] if channels else [(c, c) for c in columns]
    missing = [n for n, _ in specs if n not in columns]
    if missing:
        raise _fail(path, f"channel(s) {', '.join(missing)} not in the file; it has: "
                          f"{', '.join(columns)}")
    columns = {n: _usable(path, columns[n]) for n, _ in specs}  # the others are not read
    lengths = {c: v.size for c, v in columns.items()}
    if len(set(lengths.values())) > 1:
        raise _fail(path, f"channels have different lengths: {lengths}")
    outputs = [o for _, o in specs]
    if len(set(outputs)) < len(outputs):
        raise UsageError(f"two channels map to the same output: {', '.join(outputs)}")
    names = [n for n, _ in specs]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise UsageError(f"channel(s) {', '.join(twice)} chosen more than once: one column is "
                         "one sensor")
    unit_of = parse_units(units) if not isinstance(units, dict) else units
    known = {n for n, _ in specs} | set(outputs)
    stray = [n for n in unit_of if n is not None and n not in known]
    if stray:
        raise UsageError(f"--unit names channel(s) {', '.join(stray)} that are not chosen")
    sensitivities = sensitivities or {}
    stray = [n for n in sensitivities if n not in known]
    if stray:
        raise UsageError(f"--sensitivity names channel(s) {', '.join(stray)} that are not "
                         "chosen")
    selected, used_units, si_units, unknown_level = {}, {}, {}, []
    for name, output in specs:
        values = columns[name]
        if values.size >= 2 and np.ptp(values) == 0:
            raise _fail(path, f"channel '{name}' is constant ({values[0]:g}): a dead or "
                              "disconnected sensor?")
        _check_spikes(path, name, values)
        unit = unit_of.get(name) or unit_of.get(output) or unit_of.get(None)
        sensitivity = sensitivities.get(name) or sensitivities.get(output)
        if sensitivity:
            factor, si = sensitivity_factor(unit or "V", sensitivity)
            values = values * factor
            used_units[output] = f"{unit or 'V'} at {sensitivity} -> {si}"
            si_units[output] = si
        elif unit and is_voltage(unit):
            used_units[output] = f"{unit} (no sensitivity: the level is not known)"
            unknown_level.append(output)
        elif unit:
            factor, si = si_factor(unit)
            values = values * factor
            used_units[output] = f"{unit} -> {si}"
            si_units[output] = si
        selected[output] = np.ascontiguousarray(values, dtype=float)
    metadata = {**table.metadata, "file": str(path), "sample_rate_source": source}
    if any(n != o for n, o in specs):
        metadata["channel_map"] = {o: n for n, o in specs}
    if used_units:
        metadata["units"] = used_units
    if si_units:
        metadata["si_units"] = si_units
    if unknown_level:
        metadata["unknown_level"] = unknown_level
    return Measurement(selected, float(rate), metadata)
