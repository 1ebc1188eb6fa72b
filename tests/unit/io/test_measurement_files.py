"""Measurement files: round trip, refusal to overwrite, clear errors on bad content."""

import numpy as np
import pytest
from conftest import write_csv

from pydiag.core.errors import MeasurementError, OutputError
from pydiag.core.measurement import Measurement
from pydiag.io.measurements import write_measurement
from pydiag.io.readers import read_measurement


def test_round_trip_keeps_channels_rate_and_metadata(tmp_path):
    m = Measurement({"acc": np.sin(np.arange(100)), "disp": np.arange(100.0)}, 2000.0, {"snr": 10})
    write_measurement(tmp_path / "m.csv", m)
    back = read_measurement(tmp_path / "m.csv")
    assert back.sample_rate_hz == pytest.approx(2000.0)
    assert back.metadata == {"snr": 10, "file": str(tmp_path / "m.csv"),
                             "sample_rate_source": "column 'time_s'"}
    np.testing.assert_array_equal(back.channels["acc"], m.channels["acc"])
    assert list(read_measurement(tmp_path / "m.csv", channels=["disp"]).channels) == ["disp"]


def test_existing_file_is_not_overwritten(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("precious")
    with pytest.raises(OutputError, match="exists"):
        write_measurement(path, Measurement({"a": np.zeros(3)}, 1.0))
    assert path.read_text() == "precious"


@pytest.mark.parametrize("header,rows,kwargs,message", [
    (["time_s", "acc"], [[0, 1], [1e-4, float("nan")], [2e-4, 1]], {}, "missing or NaN value"),
    (["time_s", "acc"], [[0, 1], [1e-4, 2]], {"channels": ["disp"]}, "not in the file"),
    (["acc"], [[1], [2]], {}, "give --sample-rate"),
    (["time_s", "acc"], [[0, 1], [0, 2]], {}, "increase strictly"),
    (["time_s", "acc"], [[0, 1], [1e-4, "x"]], {}, "non-numeric"),
    (["time_s", "acc"], [[0, 1], [1e-4, 2]], {"sample_rate_hz": 5000.0}, "disagrees"),
])
def test_bad_measurements_are_refused(tmp_path, header, rows, kwargs, message):
    path = write_csv(tmp_path / "m.csv", header, rows)
    with pytest.raises(MeasurementError, match=message):
        read_measurement(path, **kwargs)


def test_unreadable_file(tmp_path):
    with pytest.raises(MeasurementError, match="cannot read"):
        read_measurement(tmp_path / "missing.csv")
    (tmp_path / "bin.csv").write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(MeasurementError, match="cannot read"):
        read_measurement(tmp_path / "bin.csv")
