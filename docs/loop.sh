#!/usr/bin/env bash
# The compare -> learn -> add -> rebuild -> compare loop of docs/loop.md, runnable:
# `make loop` (it works in a scratch folder and leaves the repository as it was).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
PYDIAG="$ROOT/.venv/bin/pydiag"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"

# 0. a "measurement": the gear pair with a pinion-bearing outer-race defect, SNR 10
"$PYDIAG" simulate --fmu "$ROOT/build/effects/BearingOuterRace.fmu" --set a_f=0.3 --set f_f=0.6 \
    --snr 10 --duration 2.4 --out meas.csv --quiet

# 1. hold the base model against it: residual peaks, named, and the suggested effect
"$PYDIAG" compare --fmu "$ROOT/build/GearPair.fmu" --measurement meas.csv --bearing 9,7.94,39.04 \
    --source "$ROOT/modelica/GearDiag/GearPair.mo" --history loop.sqlite --quiet \
    --build-dir "$ROOT/build/effects"

# 2. add the effect: a model that extends the base (here the catalogue's own), rebuild
cp -r "$ROOT/modelica" modelica
cat > modelica/GearDiag/MyGearbox.mo <<'MO'
within GearDiag;
model MyGearbox "the base gear pair plus the suggested pinion-bearing outer-race defect"
  extends GearDiag.Effects.BearingOuterRace;
end MyGearbox;
MO
"$ROOT/.venv/bin/python" -m fmu_build modelica/GearDiag/MyGearbox.mo --model GearDiag.MyGearbox \
    -o MyGearbox.fmu

# 3. compare again, fitting the effect's parameters too, and watch the error fall
"$PYDIAG" compare --fmu MyGearbox.fmu --effect bearing_outer_race --measurement meas.csv \
    --bearing 9,7.94,39.04 --source modelica/GearDiag/MyGearbox.mo --history loop.sqlite --quiet
"$PYDIAG" history --history loop.sqlite --plot "$ROOT/build/loop_history.png" --force  # a build artefact, replaced each run
