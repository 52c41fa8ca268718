#!/bin/bash
# The reporting set of the step re-timing option (control/step_retiming.py), from the
# repository root: the push sweep of gaitnet with it, then seeds 0-19 (stones, gaps, flat
# speeds). Resumable: the sweep resumes from its cases.jsonl.
set -e
export MUJOCO_GL=egl
OUT=benchmarks/results/retime_steps
.venv/bin/gaitnet-mpc sweep push --controllers gaitnet+benchmarks/configs/retime_steps.toml \
  --speeds 0.5 --workers 2 --out $OUT/sweep_push_v0.5
.venv/bin/python benchmarks/gaitnet_runs.py --seeds 20 --dts '' --flat-speeds 0.25,0.5,0.75,1.0 \
  --set retime_steps.min_dt_s=0.03 --jobs 2 --out $OUT/gaitnet_runs.md
echo ALLDONE
