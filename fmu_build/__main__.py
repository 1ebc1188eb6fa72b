"""python -m fmu_build MODEL_FILE --model NAME -o OUT.fmu"""

from __future__ import annotations

import argparse
import sys

from fmu_build.build import build_fmu
from fmu_build.errors import ModelicaBuildError


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m fmu_build",
                                     description="Build an FMI 3.0 Model-Exchange FMU from Modelica.")
    parser.add_argument("model_file", help="Modelica file holding the model (inside its package)")
    parser.add_argument("--model", required=True, help="full model name, e.g. GearDiag.GearPair")
    parser.add_argument("-o", "--output", required=True, help="FMU file to write")
    args = parser.parse_args(argv)
    try:
        path = build_fmu(args.model_file, args.model, args.output)
    except ModelicaBuildError as err:
        print(f"fmu_build: error: {err}", file=sys.stderr)
        return 2
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
