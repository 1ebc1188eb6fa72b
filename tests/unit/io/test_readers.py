"""Every reader on small generated files: the same record comes back from each format,
with its sample rate found where the format holds one; and the ways real files go wrong
(delimiters, decimal commas, BOMs, gzip, jittered time columns, duplicates, dead sensors)."""

import gzip
import json

import numpy as np
import pandas as pd
import pytest
import scipy.io
import scipy.io.wavfile

from pydiag.core.errors import MeasurementError, UsageError
from pydiag.io.readers import read_measurement

FS = 2048.0
N = 600


@pytest.fixture
def signals():
    rng = np.random.default_rng(3)
    return {"a1": rng.standard_normal(N), "a2": np.sin(np.arange(N) / 7.0)}


def _check(m, signals, rate=FS, names=("a1", "a2"), rtol=1e-12):
    assert list(m.channels) == list(names)
    assert m.sample_rate_hz == pytest.approx(rate, rel=1e-9)
    for name, original in zip(names, signals.values()):
        np.testing.assert_allclose(m.channels[name], original, rtol=rtol, atol=rtol)


def test_csv_with_time_column_gives_the_rate_and_keeps_metadata(tmp_path, signals):
    path = tmp_path / "r.csv"
    t = np.arange(N) / FS
    with open(path, "w") as fh:
        fh.write('# meta: {"rig": "test"}\n# a comment\n')
        pd.DataFrame({"time_s": t, **signals}).to_csv(fh, index=False)
    m = read_measurement(path)
    _check(m, signals)
    assert m.metadata["rig"] == "test" and m.metadata["sample_rate_source"] == "column 'time_s'"


def test_time_column_written_to_nine_digits_is_accepted(tmp_path, signals):
    """A real recorder's time column (9 significant digits) jitters by a tiny fraction of
    a sample; the old reader refused it as not uniform."""
    fs = 25_600.0
    t = np.arange(N) / fs + 10.0  # a record that starts at 10 s
    path = tmp_path / "r.csv"
    pd.DataFrame({"Time": [f"{v:.9g}" for v in t], **signals}).to_csv(path, index=False)
    m = read_measurement(path)
    assert abs(m.sample_rate_hz - fs) < 1e-4 * fs
    jittered = t.copy()
    jittered[N // 2] += 0.05 / fs  # 5 % of a sample: not a uniform record
    pd.DataFrame({"Time": jittered, **signals}).to_csv(path, index=False)
    with pytest.raises(MeasurementError, match="not uniformly sampled.*0.05"):
        read_measurement(path)


@pytest.mark.parametrize("sep,decimal", [(";", ","), ("\t", "."), ("\t", ","), (" ", ".")])
def test_delimiters_and_decimal_commas_are_sniffed(tmp_path, signals, sep, decimal):
    path = tmp_path / "r.txt"
    pd.DataFrame(signals).to_csv(path, index=False, sep=sep, decimal=decimal)
    _check(read_measurement(path, sample_rate_hz=FS), signals, rtol=1e-12)


def test_gzip_bom_and_headerless_text(tmp_path, signals):
    text = pd.DataFrame(signals).to_csv(index=False)
    bom = tmp_path / "bom.csv"
    bom.write_bytes("\ufeff".encode() + text.encode())
    _check(read_measurement(bom, FS), signals)
    gz = tmp_path / "r.csv.gz"
    gz.write_bytes(gzip.compress(text.encode()))
    _check(read_measurement(gz, FS), signals)
    bare = tmp_path / "bare.csv"
    pd.DataFrame(signals).to_csv(bare, index=False, header=False)
    _check(read_measurement(bare, FS), signals, names=("ch1", "ch2"))


def test_parquet(tmp_path, signals):
    import pyarrow as pa
    import pyarrow.parquet as pq
    table = pa.Table.from_pandas(pd.DataFrame({"time_s": np.arange(N) / FS, **signals}))
    table = table.replace_schema_metadata({**table.schema.metadata,
                                           b"pydiag": json.dumps({"rig": "pq"}).encode()})
    pq.write_table(table, tmp_path / "r.parquet")
    m = read_measurement(tmp_path / "r.parquet")
    _check(m, signals)
    assert m.metadata["rig"] == "pq"


def test_mat_v5_with_rate_variable_and_matrix(tmp_path, signals):
    path = tmp_path / "r.mat"
    scipy.io.savemat(path, {"fs": FS, "acc": signals["a1"][:, None],
                            "block": np.column_stack(list(signals.values())), "note": "text"})
    m = read_measurement(path)
    assert m.metadata["sample_rate_source"] == "the file's rate variable"
    assert set(m.channels) == {"acc", "block_1", "block_2"}
    np.testing.assert_array_equal(m.channels["block_2"], signals["a2"])
    with pytest.raises(MeasurementError, match="disagrees"):
        read_measurement(path, sample_rate_hz=2 * FS)


def test_mat_v73_through_h5py(tmp_path, signals):
    import h5py
    path = tmp_path / "r73.mat"
    with h5py.File(path, "w", userblock_size=512) as f:  # MATLAB's v7.3 layout: HDF5
        f["a1"] = signals["a1"][None, :]  # MATLAB stores column vectors transposed
        f["Fs"] = np.array([[FS]])
    with open(path, "r+b") as fh:  # the MATLAB header in the user block
        fh.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64".ljust(116) + b"\x00" * 8
                 + b"\x00\x02IM")
    m = read_measurement(path)
    np.testing.assert_array_equal(m.channels["a1"], signals["a1"])
    assert m.sample_rate_hz == FS


def test_mat_v73_struct_fields_are_channels(tmp_path, signals):
    """A v7.3 struct is an HDF5 group: its fields were not read ('no signal column')."""
    import h5py
    path = tmp_path / "s73.mat"
    with h5py.File(path, "w", userblock_size=512) as f:
        f["rec/a1"] = signals["a1"][None, :]
        f["rec/fs"] = np.array([[FS]])
        f["#refs#/x"] = np.zeros((1, 3))  # MATLAB's cell contents: not a channel
    with open(path, "r+b") as fh:
        fh.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64".ljust(116) + b"\x00" * 8
                 + b"\x00\x02IM")
    m = read_measurement(path)
    assert list(m.channels) == ["rec.a1"] and m.sample_rate_hz == FS
    np.testing.assert_array_equal(m.channels["rec.a1"], signals["a1"])


def test_a_truncated_wav_is_refused_in_one_line(tmp_path, signals):
    path = tmp_path / "r.wav"
    scipy.io.wavfile.write(path, int(FS), np.round(signals["a2"] * 16000).astype(np.int16))
    path.write_bytes(path.read_bytes()[:-1000])
    with pytest.raises(MeasurementError, match="truncated.*promises more samples") as err:
        read_measurement(path)
    assert "\n" not in str(err.value)


def test_wav_int16_is_scaled_to_full_scale(tmp_path, signals):
    data = np.column_stack([np.round(signals["a2"] * 16000), np.zeros(N)]).astype(np.int16)
    data[0, 1] = 5
    scipy.io.wavfile.write(tmp_path / "r.wav", int(FS), data)
    m = read_measurement(tmp_path / "r.wav", channels=["ch1=acc"])
    assert m.sample_rate_hz == FS and list(m.channels) == ["acc"]
    np.testing.assert_allclose(m.channels["acc"], np.round(signals["a2"] * 16000) / 32768)


def test_tdms_with_wf_increment(tmp_path, signals):
    from nptdms import ChannelObject, TdmsWriter
    with TdmsWriter(tmp_path / "r.tdms") as w:
        w.write_segment([ChannelObject("vib", name, values, properties={"wf_increment": 1 / FS})
                         for name, values in signals.items()])
    m = read_measurement(tmp_path / "r.tdms")
    _check(m, signals)
    assert m.metadata["sample_rate_source"] == "the TDMS wf_increment"


def test_channels_are_mapped_and_units_converted(tmp_path, signals):
    path = tmp_path / "r.csv"
    pd.DataFrame(signals).to_csv(path, index=False)
    m = read_measurement(path, FS, channels=["a2=acc", "a1"], units=["acc=g", "a1=mm/s**2"])
    assert list(m.channels) == ["acc", "a1"]
    np.testing.assert_allclose(m.channels["acc"], 9.80665 * signals["a2"])
    np.testing.assert_allclose(m.channels["a1"], 1e-3 * signals["a1"])
    assert m.metadata["channel_map"] == {"acc": "a2", "a1": "a1"}
    with pytest.raises(UsageError, match="unknown unit"):
        read_measurement(path, FS, units=["bananas"])
    with pytest.raises(UsageError, match="not an acceleration"):
        read_measurement(path, FS, units=["N"])


def test_volts_are_kept_without_a_sensitivity_and_converted_with_one(tmp_path, signals):
    path = tmp_path / "r.csv"
    pd.DataFrame(signals).to_csv(path, index=False)
    m = read_measurement(path, FS, units=["V"])
    np.testing.assert_array_equal(m.channels["a1"], signals["a1"])
    assert "level is not known" in m.metadata["units"]["a1"]
    m = read_measurement(path, FS, channels=["a1=acc", "a2"], units=["mV"],
                         sensitivities={"acc": "100 mV/g", "a2": "10.2 mV/(m/s2)"})
    np.testing.assert_allclose(m.channels["acc"], signals["a1"] * 1e-3 / 0.1 * 9.80665)
    np.testing.assert_allclose(m.channels["a2"], signals["a2"] / 10.2)
    with pytest.raises(UsageError, match="not a voltage"):
        read_measurement(path, FS, units=["g"], sensitivities={"a1": "100 mV/g"})
    with pytest.raises(UsageError, match="not a positive voltage per"):
        read_measurement(path, FS, sensitivities={"a1": "100 mV"})
    with pytest.raises(UsageError, match="--sensitivity names channel"):
        read_measurement(path, FS, channels=["a1"], sensitivities={"a2": "100 mV/g"})


@pytest.mark.parametrize("text,kwargs,message", [
    ("acc,acc\n1,2\n3,4\n", {"sample_rate_hz": FS}, "duplicate column name.*acc"),
    ("acc,b\n1,2\n1,5\n1,4\n", {"sample_rate_hz": FS}, "channel 'acc' is constant.*dead"),
    ("acc,b\n1,2\n,5\n1,4\n", {"sample_rate_hz": FS}, "'acc' has 1 missing.*row 2"),
    ("time_s,acc\n0,1\n", {}, "one row only"),
    ("acc\n1\n2\n", {}, "give --sample-rate"),
])
def test_bad_files_get_one_clear_line(tmp_path, text, kwargs, message):
    path = tmp_path / "r.csv"
    path.write_text(text)
    with pytest.raises(MeasurementError, match=message) as err:
        read_measurement(path, **kwargs)
    assert "\n" not in str(err.value) and str(path) in str(err.value)


def test_a_corrupt_value_is_refused_but_a_tacho_and_impacts_are_not(tmp_path):
    rng = np.random.default_rng(3)
    acc = rng.normal(size=4000)
    acc[::400] += 50.0  # a broken tooth's impacts, 50 sigma
    tacho = np.where(np.arange(4000) % 100 == 0, 5.0, 0.0)  # pulses: deviation 0 mostly
    path = tmp_path / "r.csv"
    pd.DataFrame({"acc": acc, "tacho": tacho}).to_csv(path, index=False)
    assert read_measurement(path, FS).n_samples == 4000
    acc[1234] = 9.9e37  # a DAQ's overflow code
    pd.DataFrame({"acc": acc, "tacho": tacho}).to_csv(path, index=False)
    with pytest.raises(MeasurementError, match=r"channel 'acc' sample 1234 is 9.9e\+37, .* a "
                                               "corrupt value or an overflow code"):
        read_measurement(path, FS)


def test_unknown_format_and_not_a_file(tmp_path):
    with pytest.raises(MeasurementError, match="unknown measurement format"):
        read_measurement(tmp_path / "r.xlsx")
    (tmp_path / "d.csv").mkdir()
    with pytest.raises(MeasurementError, match="not a regular file"):
        read_measurement(tmp_path / "d.csv")


def test_whitespace_aligned_text_with_leading_blanks_and_crlf(tmp_path, signals):
    """What MATLAB's save -ascii writes (the PHM 2009 records): no header, columns aligned
    by runs of blanks, a blank before each line, CRLF; read as ch1, ch2."""
    path = tmp_path / "r.txt"
    path.write_bytes("".join(f"  {a: .7e} {b: .7e}\r\n" for a, b in zip(*signals.values()))
                     .encode())
    _check(read_measurement(path, FS), signals, names=("ch1", "ch2"), rtol=1e-7)


def test_a_zip_holding_one_record_is_read_as_that_record(tmp_path, signals):
    import zipfile
    inner = tmp_path / "r.txt"
    inner.write_text("".join(f"  {a: .7e} {b: .7e}\r\n" for a, b in zip(*signals.values())))
    archive = tmp_path / "r 1.zip"
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as z:
        z.write(inner, "r 1.txt")
    m = read_measurement(archive, FS, ["ch2=acc"])
    assert list(m.channels) == ["acc"] and m.metadata["file"].endswith("r 1.zip:r 1.txt")
    np.testing.assert_allclose(m.channels["acc"], signals["a2"], rtol=1e-7)
    with zipfile.ZipFile(tmp_path / "two.zip", "w") as z:
        z.write(inner, "a.txt")
        z.write(inner, "b.txt")
    with pytest.raises(MeasurementError, match="must hold one record file, it holds 2"):
        read_measurement(tmp_path / "two.zip", FS)


@pytest.mark.parametrize("delimiter", [",", "\t", ";"])
def test_a_delimiter_ending_every_line_is_no_column(tmp_path, signals, delimiter):
    path = tmp_path / "r.csv"
    lines = [delimiter.join(["a1", "a2"]) + delimiter]
    lines += [delimiter.join(f"{v:.17g}" for v in row) + delimiter
              for row in zip(*signals.values())]
    path.write_text("\n".join(lines) + "\n")
    _check(read_measurement(path, FS), signals)


def test_a_column_not_chosen_is_not_checked(tmp_path, signals):
    """A label column (text) or a column with gaps beside the one asked for stops nothing;
    asked for, it is refused with its reason."""
    frame = pd.DataFrame({**signals, "label": ["healthy"] * N,
                          "slow": np.where(np.arange(N) % 2 == 0, 1.0, np.nan)})
    frame.to_parquet(tmp_path / "r.parquet")
    frame.to_csv(tmp_path / "r.csv", index=False)
    for name in ("r.parquet", "r.csv"):
        m = read_measurement(tmp_path / name, FS, ["a1"])
        assert list(m.channels) == ["a1"]
        with pytest.raises(MeasurementError, match="column 'label' has a non-numeric value"):
            read_measurement(tmp_path / name, FS, ["label"])
        with pytest.raises(MeasurementError, match="column 'slow' has 300 missing"):
            read_measurement(tmp_path / name, FS, ["slow"])


def test_an_empty_unit_and_a_column_chosen_twice_are_refused(tmp_path, signals):
    path = tmp_path / "r.csv"
    pd.DataFrame(signals).to_csv(path, index=False)
    with pytest.raises(UsageError, match="a unit is UNIT or NAME=UNIT, got 'a1='"):
        read_measurement(path, FS, ["a1"], ["a1="])
    with pytest.raises(UsageError, match="a1 chosen more than once"):  # one sensor, one output
        read_measurement(path, FS, ["a1=acc", "a1=disp"])
    with pytest.raises(UsageError, match="same output"):
        read_measurement(path, FS, ["a1=acc", "a2=acc"])


@pytest.mark.parametrize("fmt", ["csv", "csv.gz", "parquet", "mat", "wav", "tdms"])
def test_a_record_past_the_bound_is_refused_before_it_is_read(tmp_path, monkeypatch, fmt):
    from pydiag.io import formats
    monkeypatch.setattr(formats, "MAX_SAMPLES", 1000)
    x = np.sin(np.arange(1500) / 7.0)
    path = tmp_path / f"long.{fmt}"
    if fmt.startswith("csv"):
        pd.DataFrame({"acc": x}).to_csv(path, index=False)
    elif fmt == "parquet":
        pd.DataFrame({"acc": x}).to_parquet(path)
    elif fmt == "mat":
        scipy.io.savemat(path, {"acc": x, "fs": FS})
    elif fmt == "wav":
        scipy.io.wavfile.write(path, int(FS), (x * 1000).astype(np.int16))
    else:
        from nptdms import ChannelObject, TdmsWriter
        with TdmsWriter(path) as w:
            w.write_segment([ChannelObject("g", "acc", x, properties={"wf_increment": 1 / FS})])
    with pytest.raises(MeasurementError, match="pydiag reads at most 1,000"):
        read_measurement(path, FS)
    monkeypatch.setattr(formats, "MAX_SAMPLES", 2000)
    assert read_measurement(path, FS).n_samples == 1500


def test_fifty_million_rows_are_refused_in_little_memory(tmp_path):
    """A 50-million-row gzip (a few MB) took 11 GB: counted streamed, it is refused."""
    import gzip
    import resource
    import subprocess
    import sys
    path = tmp_path / "huge.csv.gz"
    with gzip.open(path, "wb", compresslevel=1) as fh:
        fh.write(b"acc\n")
        chunk = b"0.5\n" * 1_000_000
        for _ in range(50):
            fh.write(chunk)
    code = ("import sys\nfrom pydiag.io.readers import read_measurement\n"
            "try:\n    read_measurement(sys.argv[1], 10000.0)\n"
            "except Exception as e:\n    print(type(e).__name__, e)\n")
    res = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True,
                         text=True)
    assert "MeasurementError" in res.stdout and "at most" in res.stdout, res
    peak_kb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    assert peak_kb < 2 * 1024 * 1024, peak_kb
