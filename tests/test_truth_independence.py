"""The independent simulators share nothing with the models pydiag fits (issue 61): they
import nothing of pydiag's but the record type they write, so a bug in pydiag's
kinematics, effects or noise cannot hit the truth and the tool alike."""

import ast
from pathlib import Path

import pytest

TRUTH = Path(__file__).resolve().parent / "truth"
#: What the simulators may take from pydiag: the record they write.
ALLOWED = {"pydiag.core.measurement"}


@pytest.mark.parametrize("path", sorted(TRUTH.glob("*.py")), ids=lambda p: p.name)
def test_the_simulators_import_of_pydiag_only_the_record_they_write(path):
    imported = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            imported.add(node.module)
        elif isinstance(node, ast.Import):
            imported.update(a.name for a in node.names)
    assert {m for m in imported if m.split(".")[0] == "pydiag"} <= ALLOWED, path


def test_the_check_sees_an_import_of_pydiag():
    """Not vacuous: the simulators are read, and a pydiag import in them would be seen."""
    sources = " ".join(p.read_text() for p in TRUTH.glob("*.py"))
    assert "from pydiag.core.measurement import Measurement" in sources
    assert len(list(TRUTH.glob("*.py"))) >= 3
