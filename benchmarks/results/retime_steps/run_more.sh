#!/bin/bash
# The rest of the reporting set of the step re-timing option, from a worktree at 633937c
# (git worktree add /tmp/wt_rt 633937c): stones 20-59, uneven tiles with the preview and
# blind, the protocol's pushes, the payload sweep.
cd /tmp/wt_rt
export PYTHONPATH=/tmp/wt_rt/src MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
R=/work/main/benchmarks/results/retime_steps
S="retime_steps.min_dt_s=0.03"
C=gaitnet+benchmarks/configs/retime_steps.toml
$PY benchmarks/gaitnet_runs.py --seeds 40 --seed-offset 20 --courses stepping-stones --no-flat --dts '' --set $S --jobs 2 --out $R/stones_20_59.md
$PY benchmarks/uneven_runs.py --amplitude 0.05 --speed 0.75 --seeds 20 --jobs 2 --set $S --out $R/uneven_5cm_0.75mps.md
$PY benchmarks/uneven_runs.py --amplitude 0.03 --speed 0.5 --seeds 20 --blind --jobs 2 --set $S --out $R/uneven_3cm_0.5mps_blind.md
$PY -m gaitnet_mpc.cli.main sweep protocol --controllers $C --workers 2 --out $R/sweep_protocol
$PY -m gaitnet_mpc.cli.main sweep payload --controllers $C --speeds 0.5 --workers 2 --out $R/sweep_payload
echo ALLDONE
