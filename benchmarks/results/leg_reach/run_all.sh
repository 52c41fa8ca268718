#!/bin/bash
# Reporting set of the reach rows, run from a worktree at 624a9bc.
cd /tmp/wt_reach  # made by: git worktree add /tmp/wt_reach 624a9bc
export PYTHONPATH=/tmp/wt_reach/src MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
R=/work/main/benchmarks/results/leg_reach
S="keep_feet_in_reach=true"
$PY -m gaitnet_mpc.cli.main sweep push --controllers gaitnet+benchmarks/configs/leg_reach.toml,kd@0.045+benchmarks/configs/leg_reach.toml --speeds 0.5 --workers 2 --out $R/sweep_push_v0.5_full
$PY benchmarks/gaitnet_runs.py --seeds 20 --no-flat --dts 0.045 --courses stepping-stones,gap --set $S --jobs 2 --out $R/gaitnet_runs.md
$PY benchmarks/gaitnet_runs.py --seeds 0 --courses '' --flat-speeds 0.25,0.5,0.75,1.0 --dts '' --set $S --jobs 2 --out $R/flat_speeds.md
$PY benchmarks/uneven_runs.py --amplitude 0.05 --speed 0.75 --seeds 20 --jobs 2 --set $S --out $R/uneven_5cm_0.75mps.md
$PY benchmarks/uneven_runs.py --amplitude 0.03 --speed 0.5 --seeds 20 --blind --jobs 2 --set $S --out $R/uneven_3cm_0.5mps_blind.md
$PY -m gaitnet_mpc.cli.main sweep protocol --controllers gaitnet+benchmarks/configs/leg_reach.toml --workers 2 --out $R/sweep_protocol
$PY -m gaitnet_mpc.cli.main sweep payload --controllers gaitnet+benchmarks/configs/leg_reach.toml --speeds 0.5 --workers 2 --out $R/sweep_payload
echo ALLDONE
