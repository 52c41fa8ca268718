#!/bin/bash
# The reporting set of the option end_at_touchdown (docs/design/step_retiming.md), from the
# repository root, with benchmarks/configs/end_at_touchdown.toml. Resumable: the sweeps
# resume, and a finished report is not run again.
export MUJOCO_GL=egl OMP_NUM_THREADS=1
R=benchmarks/results/end_at_touchdown
S="dt_policy.gaitnet.retime_steps.end_at_touchdown=true"
C=gaitnet+benchmarks/configs/end_at_touchdown.toml
PY=.venv/bin/python
$PY -m gaitnet_mpc.cli.main sweep push --controllers $C --speeds 0.5 --workers 2 --out $R/sweep_push_v0.5
[ -e $R/gaitnet_runs.md ] || $PY benchmarks/gaitnet_runs.py --seeds 20 --dts '' --courses stepping-stones,gap --no-flat --jobs 2 --set $S --out $R/gaitnet_runs.md
$PY -m gaitnet_mpc.cli.main sweep protocol --controllers $C --workers 2 --out $R/sweep_protocol
[ -e $R/stones_20_59.md ] || $PY benchmarks/gaitnet_runs.py --seeds 40 --seed-offset 20 --courses stepping-stones --no-flat --dts '' --jobs 2 --set $S --out $R/stones_20_59.md
[ -e $R/uneven_5cm_0.75mps.md ] || $PY benchmarks/uneven_runs.py --amplitude 0.05 --speed 0.75 --seeds 20 --jobs 2 --set $S --out $R/uneven_5cm_0.75mps.md
[ -e $R/uneven_3cm_0.5mps_blind.md ] || $PY benchmarks/uneven_runs.py --amplitude 0.03 --speed 0.5 --seeds 20 --blind --jobs 2 --set $S --out $R/uneven_3cm_0.5mps_blind.md
[ -e $R/gaitnet_flat_speeds.md ] || $PY benchmarks/gaitnet_runs.py --seeds 0 --dts '' --courses '' --flat-speeds 0.25,0.5,0.75,1.0 --jobs 2 --set $S --out $R/gaitnet_flat_speeds.md
echo ALLDONE
