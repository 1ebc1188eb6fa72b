"""The record's facts as compare and diagnose print them: a gain curve says it is one."""

from pydiag.app.formatting import format_facts


def test_the_gains_line_says_whether_each_gain_is_a_number_or_a_curve():
    one = format_facts({"gains": {"acc": 0.5}})
    curve = format_facts({"gains": {"acc": 0.5}, "gain_curve": True})
    assert one == "gains      : acc x0.5 (model -> measurement level)"
    assert curve == ("gains      : acc x0.5 (model -> measurement: each a gain curve, its "
                     "value at the first mesh harmonic)")
