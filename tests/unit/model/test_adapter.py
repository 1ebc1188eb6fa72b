"""Adapter files: every mistake names the file, the table and the key."""

import pytest

from pydiag.core.errors import AdapterError
from pydiag.model.adapter import load_adapter, parse_adapter

# ---------------------------------------------------------------------- adapters

MINIMAL = {"sensor": [{"variable": "y"}], "fault_parameter": [{"variable": "k", "low": 0, "high": 1}],
           "spectrum": {"window_s": 1.0, "max_freq_hz": 10.0}}


@pytest.mark.parametrize("change,message", [
    ({"extra": 1}, "unknown key"),
    ({"sensor": []}, r"at least one \[\[sensor\]\]"),
    ({"fault_parameter": [{"variable": "k", "low": 1, "high": 1}]}, "low < high"),
    ({"fault_parameter": [{"variable": "k", "low": "a", "high": 1}]}, "'low' must be a number"),
    ({"simulation": {"engine": "turbo"}}, "engine must be one of"),
    ({"kinematics": {"n_pinion": 14, "n_gear": 21, "f_pinion_hz": 25}}, "not both"),
    ({"spectrum": None}, r"give \[kinematics\]"),
    ({"start_values": {"k": "x"}}, "must be a finite number"),
    ({"sensor": [{"variable": "y"}, {"variable": "y"}]}, "channels must be unique"),
    ({"fault_parameter": [{"variable": "k", "low": 0, "high": float("inf")}]},
     "'high' must be a finite number, got inf"),
    ({"start_values": {"k": float("nan")}}, "'k' must be a finite number"),
    ({"simulation": {"warmup_s": 1e6}}, r"'warmup_s' must lie in \[0, 100\] s"),
    ({"simulation": {"warmup_s": -1}}, r"'warmup_s' must lie in"),
    ({"simulation": {"eval_timeout_s": 0}}, "'eval_timeout_s' must be positive"),
])
def test_adapter_validation_names_the_key(change, message):
    data = {**MINIMAL, **change}
    data = {k: v for k, v in data.items() if v is not None}
    with pytest.raises(AdapterError, match=message):
        parse_adapter(data, "a.toml")


def test_adapter_file_errors(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[sensor\n")
    with pytest.raises(AdapterError, match="not valid TOML"):
        load_adapter(bad)
    with pytest.raises(AdapterError, match="cannot read adapter"):
        load_adapter(tmp_path / "missing.toml")


def test_non_utf8_adapter_names_the_file(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes('[simulation]\n# Drehzahl in U/min, Übersetzung\n'.encode("latin-1"))
    with pytest.raises(AdapterError, match=r"latin1\.toml: not UTF-8 text"):
        load_adapter(path)


def test_whole_teeth_only():
    """n_pinion = 14.6 was rounded to 15 without a word."""
    data = {**MINIMAL, "spectrum": None,
            "kinematics": {"n_pinion": {"parameter": "z1"}, "n_gear": 21, "f_pinion_hz": 25}}
    adapter = parse_adapter({k: v for k, v in data.items() if v is not None}, "a.toml")
    assert adapter.resolve_kinematics({"z1": 14.0}).n_pinion == 14
    with pytest.raises(AdapterError, match=r"a.toml: \[kinematics\] n_pinion is 14.6: a number "
                                           "of teeth must be whole"):
        adapter.resolve_kinematics({"z1": 14.6})


def test_the_adapter_sets_the_evaluation_timeout():
    adapter = parse_adapter({**MINIMAL, "simulation": {"eval_timeout_s": 2.5}}, "a.toml")
    assert adapter.eval_timeout_s == 2.5
    assert parse_adapter(MINIMAL, "a.toml").eval_timeout_s is None


def test_fixed_teeth_that_contradict_the_operating_point_are_refused():
    """An adapter's fixed teeth overrode --teeth without a word."""
    from pydiag.core.errors import UsageError
    from pydiag.gear.kinematics import GearKinematics
    data = {**MINIMAL, "spectrum": None,
            "kinematics": {"n_pinion": 14, "n_gear": 21, "f_pinion_hz": {"parameter": "n"}}}
    adapter = parse_adapter({k: v for k, v in data.items() if v is not None}, "a.toml")
    assert adapter.kinematic_values(GearKinematics(14, 21, 30.0)) == {"n": 30.0}
    with pytest.raises(UsageError, match=r"a.toml: \[kinematics\] fixes n_pinion = 14 .* "
                                         "asks for 32"):
        adapter.kinematic_values(GearKinematics(32, 21, 30.0))
