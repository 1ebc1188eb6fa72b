"""Batch diagnosis: local processes and a Dask cluster give the same rows; failures are rows."""

import numpy as np
import pandas as pd
import pytest
from conftest import run_cli

from pydiag.app import batch

TINY = dict(n_particles=4, iterations=2, polish_evaluations=10, polish_starts=1, seed=7)


@pytest.fixture(scope="module")
def measurement_dir(tmp_path_factory, gear_fmu):
    folder = tmp_path_factory.mktemp("batch")
    for name, sets in (("a.csv", ["a_f=0.3"]), ("b.csv", ["f_ate=0.2", "f_dte=0.2"])):
        res = run_cli("-m", "pydiag", "simulate", "--fmu", str(gear_fmu), *sum([["--set", s] for s in sets], []),
                      "--duration", "0.24", "--snr", "10", "--out", str(folder / name), "--quiet")
        assert res.returncode == 0, res.stderr
    text = (folder / "a.csv").read_text().splitlines()
    text[5] = ",".join(text[5].split(",")[:-1] + ["nan"])
    (folder / "c_broken.csv").write_text("\n".join(text) + "\n")
    return folder


def tasks_for(folder, fmu):
    return [batch.BatchTask(p, str(fmu), TINY) for p in batch.find_measurements(str(folder))]


def test_local_batch_rows_in_order_with_failures_as_rows(measurement_dir, gear_fmu):
    rows = batch.run_batch(tasks_for(measurement_dir, gear_fmu), "local", n_workers=2)
    assert [r["measurement"].rsplit("/", 1)[1] for r in rows] == ["a.csv", "b.csv", "c_broken.csv"]
    assert [r["status"] for r in rows] == ["ok", "ok", "error"]
    assert "NaN" in rows[2]["message"]
    assert 4 * 2 < rows[0]["evaluations"] <= 4 * 2 + 10
    serial = batch.run_batch(tasks_for(measurement_dir, gear_fmu), "local", n_workers=1)
    for a, b in zip(rows, serial):
        assert {k: v for k, v in a.items() if k != "elapsed_s"} == \
               {k: v for k, v in b.items() if k != "elapsed_s"}


def test_dask_local_cluster_gives_the_same_rows(measurement_dir, gear_fmu):
    distributed = pytest.importorskip("dask.distributed")
    local = batch.run_batch(tasks_for(measurement_dir, gear_fmu), "local", n_workers=2)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        rows = batch.run_batch(tasks_for(measurement_dir, gear_fmu), client)
    for a, b in zip(local, rows):
        assert a["status"] == b["status"]
        if a["status"] == "ok":
            assert [a[k] for k in ("a_f", "f_f", "f_ate", "f_dte", "error")] == \
                   [b[k] for k in ("a_f", "f_f", "f_ate", "f_dte", "error")]


def test_cli_batch_writes_parquet_and_never_overwrites(measurement_dir, gear_fmu, tmp_path):
    out = tmp_path / "results.parquet"
    args = ["-m", "pydiag", "batch", "--fmu", str(gear_fmu), "--measurements",
            str(measurement_dir / "*.csv"), "--out", str(out), "--particles", "4",
            "--iterations", "2", "--polish", "0", "--quiet"]
    res = run_cli(*args)
    assert res.returncode == 0, res.stderr
    table = pd.read_parquet(out)
    assert len(table) == 3 and list(table["status"]) == ["ok", "ok", "error"]
    assert {"a_f", "f_f", "f_ate", "f_dte", "fault_mode", "severity", "error", "elapsed_s"} <= set(table)
    assert np.isfinite(table["a_f"][:2]).all()
    before = out.read_bytes()
    res = run_cli(*args)
    assert res.returncode == 2 and "exists" in res.stderr and out.read_bytes() == before
    res = run_cli("-m", "pydiag", "batch", "--fmu", str(gear_fmu), "--measurements",
                  str(tmp_path / "none*.csv"), "--out", str(tmp_path / "x.parquet"), "--quiet")
    assert res.returncode == 2 and "no measurement files" in res.stderr


def test_batch_rows_can_carry_the_condition_indicators(measurement_dir, gear_fmu, tmp_path):
    from pydiag.gear.indicators import INDICATORS, condition_indicators
    from pydiag.gear.kinematics import GearKinematics
    from pydiag.io.readers import read_measurement

    path = str(measurement_dir / "a.csv")
    row, = batch.run_batch([batch.BatchTask(path, str(gear_fmu), TINY, indicators="pinion")],
                           "local", n_workers=1)
    assert row["status"] == "ok", row["message"]
    direct = condition_indicators(read_measurement(path), GearKinematics(14, 21, 25.0))
    for channel in ("acc", "disp"):
        for name in INDICATORS:
            assert row[f"{channel}:{name}"] == pytest.approx(direct.indicators[channel][name],
                                                             nan_ok=True)
    out = tmp_path / "fleet.parquet"
    res = run_cli("-m", "pydiag", "batch", "--fmu", str(gear_fmu), "--measurements", path,
                  "--out", str(out), "--indicators", "--particles", "4", "--iterations", "2",
                  "--polish", "0", "--quiet")
    assert res.returncode == 0, res.stderr
    assert {"acc:fm4", "disp:na4", "acc:ser", "tooth_contrast"} <= set(pd.read_parquet(out))


def test_cli_batch_by_the_machines_own_model(measurement_dir, tmp_path):
    """batch --machine without --fmu: the machine's own model is written and built once,
    every record diagnosed by it (a column group a stage) as diagnose --machine does, a
    broken record a row; without a machine file either, a usage error."""
    out = tmp_path / "results.csv"
    res = run_cli("-m", "pydiag", "batch", "--machine", "examples/paper_pair.toml",
                  "--measurements", str(measurement_dir / "*.csv"), "--out", str(out),
                  "--quiet", "--build-dir", str(tmp_path / "build"), "--workers", "2")
    assert res.returncode == 0, res.stderr
    table = pd.read_csv(out)
    assert list(table["status"]) == ["ok", "ok", "error"], table["message"]
    # a: a_f 0.3; b: f_ate = f_dte = 0.2 (Table 1 case 6)
    assert list(table["pair:fault_mode"][:2]) == ["tooth_fault", "transmission_error"]
    assert list(table["pair:severity"][:2]) == ["medium", "medium"]
    assert len(list((tmp_path / "build" / "machines").glob("*/*.fmu"))) == 1
    res = run_cli("-m", "pydiag", "batch", "--measurements", str(measurement_dir / "*.csv"),
                  "--out", str(tmp_path / "x.csv"), "--quiet")
    assert res.returncode == 2 and "give --fmu, or --machine FILE" in res.stderr, res.stderr
