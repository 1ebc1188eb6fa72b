"""Modelica -> FMU: rumoca flattens, CasADi causalises and exports an FMI 3.0 ME FMU.

Pipeline (one module each):

- :mod:`fmu_build.flatten`     rumoca front end: variables with roles, residual equations, functions
- :mod:`fmu_build.expressions` rumoca expression trees -> CasADi SX (functions are inlined)
- :mod:`fmu_build.causalise`   residual DAE -> explicit ODE + outputs
- :mod:`fmu_build.fmu_export`  CasADi DaeBuilder -> compiled, packed FMU
"""

from fmu_build.errors import ModelicaBuildError

__all__ = ["ModelicaBuildError", "build_fmu"]


def __getattr__(name: str):
    """``build_fmu``, imported on first use: CasADi and rumoca load then, not with the
    error types (every process that runs an FMU imports those, and a forked worker copies
    what its parent loaded)."""
    if name == "build_fmu":
        from fmu_build.build import build_fmu
        return build_fmu
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
