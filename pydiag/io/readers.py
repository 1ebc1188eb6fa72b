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

import gzip
import shutil
from pathlib import Path

import numpy as np

from pydiag.core.errors import PydiagError, UsageError
from pydiag.core.measurement import Measurement
from pydiag.io.formats import (READERS, TEXT_SUFFIXES, Unusable, fail,
                                gzipped, read_text)
from pydiag.io.units import is_voltage, sensitivity_factor, si_factor

TIME_COLUMNS = ("time_s", "time", "t")
#: A time column is uniform when every sample lies this close to the grid, in samples.
TIME_TOLERANCE = 0.01
#: A given sample rate must agree with the file's this closely (relative).
RATE_TOLERANCE = 1e-3
#: A sample this many times the channel's median absolute deviation from its median is refused.
MAX_SPIKE = 1e6
SUFFIXES = TEXT_SUFFIXES + (".parquet", ".mat", ".wav", ".tdms", ".zip")
#: The largest record a zip may hold, bytes uncompressed (a 4 s record of three channels
#: at 66.7 kHz as text is 13 MB).
MAX_ZIPPED_BYTES = 2 * 1024 ** 3

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
                raise fail(path, f"a zip must hold one record file, it holds {len(members)}"
                                  + (f": {', '.join(m.filename for m in members[:5])}"
                                     if members else ""))
            member = members[0]
            name = Path(member.filename).name
            if _suffix(Path(name)) not in SUFFIXES or _suffix(Path(name)) == ".zip":
                raise fail(path, f"its record {name} is of no format pydiag reads")
            if member.file_size > MAX_ZIPPED_BYTES:
                raise fail(path, f"its record {name} is {member.file_size / 1e9:.1f} GB "
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
        raise fail(path, f"cannot read the zip: {err}") from err
    return Measurement(m.channels, m.sample_rate_hz,
                       {**m.metadata, "file": f"{path}:{member.filename}"})


def _usable(path: Path, column: np.ndarray | Unusable) -> np.ndarray:
    if isinstance(column, Unusable):
        raise fail(path, str(column))
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
        raise fail(path, f"channel '{name}' holds one value ({np.median(values):g}) in all but "
                          f"{moving} of its {values.size} samples: a dead sensor with glitches?")
    if mad > 0 and deviation[worst] > MAX_SPIKE * mad:
        raise fail(path, f"channel '{name}' sample {worst} is {values[worst]:g}, "
                          f"{deviation[worst] / mad:.2g} times the channel's median deviation: "
                          "a corrupt value or an overflow code?")


def is_measurement_file(path: str | Path) -> bool:
    """Whether the name has an extension pydiag reads."""
    return _suffix(Path(path)) in SUFFIXES


def _time_rate(path: Path, name: str, t: np.ndarray) -> float:
    """The rate of a uniform time column; MeasurementError otherwise."""
    if t.size < 2:
        raise fail(path, "one row only: a record needs at least two samples")
    if np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise fail(path, f"'{name}' must increase strictly (data rows {k + 1} and {k + 2})")
    dt = (t[-1] - t[0]) / (t.size - 1)
    deviation = float(np.max(np.abs(t - (t[0] + dt * np.arange(t.size))))) / dt
    if deviation > TIME_TOLERANCE:
        raise fail(path, f"'{name}' is not uniformly sampled: a sample lies {deviation:.3g} "
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
        raise fail(path, f"unknown measurement format '{suffix or path.name}'; pydiag reads "
                          f"{', '.join(SUFFIXES)} (text also gzipped)")
    if gzipped(path) and suffix not in TEXT_SUFFIXES:
        raise fail(path, f"only text records can be gzipped, not '{suffix}'")
    if not path.is_file():
        raise fail(path, "cannot read: no such file" if not path.exists() else
                    "cannot read: not a regular file")
    if suffix == ".zip":
        return _read_zipped(path, sample_rate_hz, channels, units, sensitivities)
    try:
        table = (read_text if suffix in TEXT_SUFFIXES else READERS[suffix])(path)
    except (OSError, EOFError, UnicodeDecodeError, gzip.BadGzipFile) as err:
        raise fail(path, f"cannot read: {getattr(err, 'strerror', None) or err}") from err
    columns = dict(table.columns)
    rate, source = table.rate_hz, table.rate_source
    time_name = next((c for c in columns if c.lower() in TIME_COLUMNS), None)
    if time_name is not None:
        rate, source = _time_rate(path, time_name, _usable(path, columns.pop(time_name))), \
            f"column '{time_name}'"
    if rate is not None and sample_rate_hz is not None:
        if abs(rate - sample_rate_hz) > RATE_TOLERANCE * rate:
            raise fail(path, f"--sample-rate {sample_rate_hz:g} Hz disagrees with {source} "
                              f"({rate:.8g} Hz)")
    elif rate is None:
        if sample_rate_hz is None:
            raise fail(path, "the file has no time column or sample rate; give --sample-rate")
        rate, source = float(sample_rate_hz), "--sample-rate"
    if not columns:
        raise fail(path, "no signal column")
    specs = [parse_channel(s) for s in channels] if channels else [(c, c) for c in columns]
    missing = [n for n, _ in specs if n not in columns]
    if missing:
        raise fail(path, f"channel(s) {', '.join(missing)} not in the file; it has: "
                          f"{', '.join(columns)}")
    columns = {n: _usable(path, columns[n]) for n, _ in specs}  # the others are not read
    lengths = {c: v.size for c, v in columns.items()}
    if len(set(lengths.values())) > 1:
        raise fail(path, f"channels have different lengths: {lengths}")
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
            raise fail(path, f"channel '{name}' is constant ({values[0]:g}): a dead or "
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
