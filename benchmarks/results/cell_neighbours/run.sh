#!/bin/sh
# The five cells where gaitnet is below the best other controller
# (../sweep_push_scan/README.md), at neighbouring push phases: is the gap systematic?
set -e
G=.venv/bin/gaitnet-mpc
$G sweep push --controllers gaitnet,kd@0.045 --speeds 0.5 --directions fwd,fwd-left,right,fwd-right \
    --phases 0.7,0.8 --workers 2 --out benchmarks/results/cell_neighbours/p075
$G sweep push --controllers gaitnet,kd@0.065 --speeds 0.5 --directions bwd \
    --phases 0.05,0.1 --workers 2 --out benchmarks/results/cell_neighbours/bwd_p0
