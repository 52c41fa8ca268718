#!/bin/bash
# The rest of the reporting set at the new defaults (the landing rule on, the re-timing
# gated by the eq. 24 box), from the repository root. A finished report is not run again.
export MUJOCO_GL=egl OMP_NUM_THREADS=1
R=benchmarks/results/landing_and_box
PY=.venv/bin/python
[ -e $R/gaitnet_flat_speeds.md ] || $PY benchmarks/gaitnet_runs.py --seeds 0 --dts '' --courses '' --flat-speeds 0.25,0.5,0.75,1.0 --jobs 2 --out $R/gaitnet_flat_speeds.md
[ -e $R/uneven_5cm_0.75mps.md ] || $PY benchmarks/uneven_runs.py --amplitude 0.05 --speed 0.75 --seeds 20 --jobs 2 --out $R/uneven_5cm_0.75mps.md
[ -e $R/uneven_3cm_0.5mps_blind.md ] || $PY benchmarks/uneven_runs.py --amplitude 0.03 --speed 0.5 --seeds 20 --blind --jobs 2 --out $R/uneven_3cm_0.5mps_blind.md
echo ALLDONE
