"""Clean stepping-stone crossings under tiny initial perturbations, any KDWalkConfig overrides:
python stones_mc.py DT N 'JSON'  -> N runs with base x offsets i * 1e-5 m (i = 1..N), the
episodes of benchmarks/kd_stones_rate.py with the configuration from the overrides."""
import json, sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "benchmarks"))
from kd_stones_rate import run
from overrides import kd_config

dt, n, ov = float(sys.argv[1]), int(sys.argv[2]), json.loads(sys.argv[3])
with ProcessPoolExecutor(2) as pool:
    res = list(pool.map(run, [(kd_config(ov), dt, i) for i in range(1, n + 1)]))
print(f"dt {dt} {ov}: clean crossings {sum(r['clean'] for r in res)}/{n}; "
      f"no fall {sum(not r['fell'] for r in res)}/{n}; "
      f"distances {[round(r['distance_m'], 2) for r in res]}; "
      f"violations {[r['violations'] for r in res]}", flush=True)
