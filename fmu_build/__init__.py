"""Modelica -> FMU: rumoca flattens, CasADi causalises and exports an FMI 3.0 ME FMU.

Pipeline (one module each):

- :mod:`fmu_build.flatten`     rumoca front end: variables with roles, residual equations, functions
- :mod:`fmu_build.expressions` rumoca expression trees -> CasADi SX (functions are inlined)
- :mod:`fmu_build.causalise`   residual DAE -> explicit ODE + outputs
- :mod:`fmu_build.fmu_export`  CasADi DaeBuilder -> compiled, packed FMU
"""

from fmu_build.errors import ModelicaBuildError
from fmu_build.build import build_fmu

__all__ = ["ModelicaBuildError", "build_fmu"]
