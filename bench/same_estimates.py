"""Are two runs of bench/paper_cases.py --json the same, to the last bit?

    .venv/bin/python bench/same_estimates.py before.json after.json

Prints, per run that differs, what differs, and a summary line; exit status 0 when every
run is identical (parameters, error, evaluations, best-error history).
"""

import json
import sys


def main() -> int:
    before, after = (json.load(open(p)) for p in sys.argv[1:3])
    keys = sorted(set(before) | set(after))
    differing = []
    for key in keys:
        a, b = before.get(key), after.get(key)
        if a != b:
            fields = [f for f in ("parameters", "error", "evaluations", "history")
                      if (a or {}).get(f) != (b or {}).get(f)]
            differing.append(key)
            print(f"run {key}: {', '.join(fields) or 'missing'} differ")
    print(f"{len(keys) - len(differing)} of {len(keys)} runs identical (parameters, error, "
          "evaluations, best-error history)")
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main())
