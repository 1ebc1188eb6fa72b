"""The eight simulated cases of the source paper's Table 1 (a0 = 0.1 throughout)."""

from __future__ import annotations

from dataclasses import dataclass

from pydiag.core.errors import UsageError


@dataclass(frozen=True)
class PaperCase:
    number: int
    name: str
    parameters: dict
    fault_mode: str
    severity: str


TABLE1 = (
    PaperCase(1, "good condition", dict(a_f=0.1, f_f=0.1, f_ate=0.0, f_dte=0.0), "healthy", "none"),
    PaperCase(2, "tooth fault, early", dict(a_f=0.2, f_f=0.4, f_ate=0.0, f_dte=0.0), "tooth_fault", "early"),
    PaperCase(3, "tooth fault, medium", dict(a_f=0.3, f_f=0.6, f_ate=0.0, f_dte=0.0), "tooth_fault", "medium"),
    PaperCase(4, "tooth fault, advanced", dict(a_f=0.6, f_f=0.9, f_ate=0.0, f_dte=0.0), "tooth_fault", "advanced"),
    PaperCase(5, "transmission error, early", dict(a_f=0.1, f_f=0.1, f_ate=0.1, f_dte=0.1), "transmission_error", "early"),
    PaperCase(6, "transmission error, medium", dict(a_f=0.1, f_f=0.1, f_ate=0.2, f_dte=0.2), "transmission_error", "medium"),
    PaperCase(7, "transmission error, advanced", dict(a_f=0.1, f_f=0.1, f_ate=0.4, f_dte=0.4), "transmission_error", "advanced"),
    PaperCase(8, "all faults, medium", dict(a_f=0.3, f_f=0.6, f_ate=0.2, f_dte=0.2), "combined", "medium"),
)


def case(number: int) -> PaperCase:
    for c in TABLE1:
        if c.number == number:
            return c
    raise UsageError(f"Table 1 has cases 1..8, not {number}")
