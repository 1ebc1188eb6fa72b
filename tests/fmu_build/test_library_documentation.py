"""The Modelica library is written as the Standard Library is: every class a file with a
documentation annotation, every Real parameter with its unit ("1" when it has none) and a
description."""

import re
from pathlib import Path

import pytest

LIBRARY = Path(__file__).resolve().parents[2] / "modelica" / "GearDiag"
FILES = sorted(LIBRARY.rglob("*.mo"))


@pytest.mark.parametrize("path", FILES, ids=lambda p: str(p.relative_to(LIBRARY)))
def test_every_class_is_documented_and_its_parameters_have_units(path):
    text = path.read_text()
    assert re.search(r"annotation\s*\(\s*Documentation\s*\(\s*info\s*=", text), path
    code = re.sub(r"//[^\n]*", "", text)
    for statement in code.split(";"):  # a declaration may span lines
        statement = " ".join(statement.split())
        declared = re.match(r"parameter Real (\w+)(\[[^\]]*\])? ?(\((?:[^()]|\([^()]*\))*\))? ?=",
                            statement)
        if declared is None or declared.group(2):  # an array's unit is its use's
            continue
        assert 'unit="' in (declared.group(3) or ""), statement
        assert re.search(r'"[^"]+"$', statement), statement  # its description

def test_the_library_has_every_class_it_lists():
    assert len(FILES) >= 36


def test_the_check_reads_the_librarys_declarations():
    """The check above reads declarations as the library writes them (modifiers with
    their own parentheses, several lines): it is not vacuous."""
    checked = 0
    for path in FILES:
        code = " ".join(re.sub(r"//[^\n]*", "", path.read_text()).split())
        checked += len(re.findall(r'parameter Real \w+ ?\((?:[^()]|\([^()]*\))*unit="', code))
    assert checked >= 60, checked
