"""What the `gaitnet` loop feeds Gait-Net, beside what its teacher's data set holds
(issue 49, item 2: the mismatch between teacher and student).

Each net drives `gaitnet` on flat ground at four speeds and on seeded stones and gaps; every
step start's input (the 16 features of its last call to the network, ``summary.json``'s
``dt_policy.steps[].features``) is collected and compared, feature by feature, with the
rows of the data set the net was trained on: the shift of the mean in the teacher's
standard deviations, the two-sample Kolmogorov-Smirnov statistic, and the share of the
loop's inputs outside the teacher's 1-99 % range. A figure overlays the histograms.

    .venv/bin/python benchmarks/feature_shift.py [--nets humanoid3d-wbmpc,humanoid3d-dagger] \
        [--seeds 10] [--jobs 2] [--out feature_shift.md]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from common import RESULTS, ROOT, command_line, machine_info, run_pool, write_report

#: Each net and the data set it was trained on (rows of the teacher's own walking; the
#: DAgger net also learnt from the states of `data/rollout-labels`, not compared here).
DATA = {
    "humanoid3d-wbmpc": "data/gaitnet-wbmpc-humanoid3d",
    "humanoid3d-kd": "data/gaitnet-kd-humanoid3d",
    "humanoid3d-dagger": "data/gaitnet-kd-humanoid3d",
}
#: A feature whose teacher and student distributions are at most this far apart (KS) is
#: one the two controllers share.
SHARED_KS = 0.2
FLAT_SPEEDS_MPS = (0.25, 0.5, 0.75, 1.0)
FLAT_S, SEEDED_S, SEEDED_VX_MPS = 10.0, 8.0, 0.75


def run(job: tuple[str, str, float, int | None]) -> dict:
    from gaitnet_mpc.scenario import make_scenario, run_scenario

    net, course, vx, seed = job
    scenario = make_scenario(
        controller="gaitnet",
        gaitnet_weights=net,
        course=course,
        course_seed=seed,
        vx_mps=vx,
        duration_s=FLAT_S if course == "flat" else SEEDED_S,
    )
    s = run_scenario(scenario)
    steps = (s.get("dt_policy") or {}).get("steps", [])
    return {
        "features": [st["features"] for st in steps if st.get("features") is not None],
        "dts": [st["dts_s"][-1] for st in steps if st["dts_s"]],
        "fell": bool(s["fell"]),
    }


def ks_statistic(a: np.ndarray, b: np.ndarray) -> float:
    from scipy.stats import ks_2samp

    return float(ks_2samp(a, b).statistic)


def main() -> None:
    from gaitnet_mpc.dataset.schema import FEATURE_NAMES
    from gaitnet_mpc.gaitnet.data import load_dataset

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nets", default="humanoid3d-wbmpc,humanoid3d-dagger")
    parser.add_argument("--seeds", type=int, default=10, help="seeded stones and gaps 0..N-1")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default="feature_shift.md")
    args = parser.parse_args()
    nets = [n for n in args.nets.split(",") if n]
    for net in nets:
        if net not in DATA:
            parser.error(f"--nets: {net!r} is not one of {sorted(DATA)}")
    cases = [("flat", v, None) for v in FLAT_SPEEDS_MPS] + [
        (course, SEEDED_VX_MPS, seed)
        for course in ("stepping-stones", "gap")
        for seed in range(args.seeds)
    ]
    jobs = [(net, *case) for net in nets for case in cases]
    t0 = time.perf_counter()
    results = run_pool(run, jobs, args.jobs, describe=lambda j, r: f"{j}: {len(r['dts'])} steps")
    wall_s = time.perf_counter() - t0

    lines = [
        "# Gait-Net's inputs in the loop beside its teacher's data",
        "",
        machine_info(),
        "",
        f"humanoid3d, `gaitnet` with each net, default settings: flat {FLAT_S:g} s at "
        f"{', '.join(f'{v:g}' for v in FLAT_SPEEDS_MPS)} m/s; seeded stepping stones and gaps "
        f"0-{args.seeds - 1}, {SEEDED_S:g} s at {SEEDED_VX_MPS:g} m/s. Loop rows: every step "
        "start's last input to the network. Shift: (loop mean - data mean) / data std. KS: "
        "two-sample Kolmogorov-Smirnov statistic (0: same distribution, 1: disjoint). "
        "Outside: share of loop rows outside the data's 1-99 % range.",
        "",
    ]
    loops: dict[str, np.ndarray] = {}
    datas: dict[str, np.ndarray] = {}
    for net in nets:
        data = load_dataset(ROOT / DATA[net])
        rows = [f for j in jobs if j[0] == net for f in results[j]["features"]]
        dts = np.array([d for j in jobs if j[0] == net for d in results[j]["dts"]])
        falls = sum(results[j]["fell"] for j in jobs if j[0] == net)
        x = np.asarray(rows, dtype=float).reshape(-1, len(FEATURE_NAMES))
        loops[net], datas[net] = x, data.x
        lo, hi = np.percentile(data.x, [1, 99], axis=0)
        outside_any = np.mean(np.any((x < lo) | (x > hi), axis=1)) if len(x) else float("nan")
        lines += [
            f"## `{net}` (data: `{DATA[net]}`, teacher `{data.teacher}`"
            + (", without its DAgger rows" if "dagger" in net else "")
            + ")",
            "",
            f"{len(x)} loop rows from {len([j for j in jobs if j[0] == net])} runs ({falls} "
            f"fell); {len(data.x)} data rows. Chosen dt in the loop: median "
            f"{np.median(dts) * 1e3:.1f} ms, {np.mean(dts >= 0.0695) * 100:.0f} % at the 70 ms "
            f"bound; data labels: median {np.median(data.y) * 1e3:.1f} ms. Loop rows with at "
            f"least one feature outside the data's 1-99 % range: {outside_any * 100:.0f} %.",
            "",
            "| feature | data mean (std) | loop mean (std) | shift [std] | KS | outside |",
            "|---|---|---|---|---|---|",
        ]
        mu, sd = data.x.mean(axis=0), data.x.std(axis=0)
        order = np.argsort([-ks_statistic(data.x[:, i], x[:, i]) for i in range(x.shape[1])])
        for i in order:
            name, col = FEATURE_NAMES[i], x[:, i]
            shift = (col.mean() - mu[i]) / sd[i] if sd[i] > 0 else float("nan")
            out = np.mean((col < lo[i]) | (col > hi[i]))
            lines.append(
                f"| {name} | {mu[i]:+.3f} ({sd[i]:.3f}) | {col.mean():+.3f} ({col.std():.3f}) | "
                f"{shift:+.2f} | {ks_statistic(data.x[:, i], col):.2f} | {out * 100:.0f} % |"
            )
        lines.append("")
    lines += _data_sets_table()
    out = Path(args.out) if Path(args.out).parent != Path() else RESULTS / args.out
    figure = out.with_suffix(".png")
    _plot(loops, datas, figure)
    shown = figure.relative_to(ROOT) if figure.is_relative_to(ROOT) else figure
    lines += [
        f"Figure: `{shown}` (histograms per net: its data filled, the loop's inputs as a line).",
        "",
        f"{len(jobs)} episodes in {wall_s / 60:.1f} min on {args.jobs} processes. "
        f"Command: `{command_line()}`.",
        "",
    ]
    write_report(out, "\n".join(lines))


def _data_sets_table() -> list[str]:
    """The whole-body teacher's data beside the `kd` student's own (both collected with the
    paper's protocol: flat, 0-1 m/s, drawn step durations, pushes): which features the two
    controllers share (KS <= :data:`SHARED_KS`)."""
    from gaitnet_mpc.dataset.schema import FEATURE_NAMES
    from gaitnet_mpc.gaitnet.data import load_dataset

    teacher = load_dataset(ROOT / DATA["humanoid3d-wbmpc"])
    student = load_dataset(ROOT / DATA["humanoid3d-kd"])
    lines = [
        "## Teacher and student under the same protocol",
        "",
        f"`{DATA['humanoid3d-wbmpc']}` ({len(teacher.x)} rows, `wbmpc`) beside "
        f"`{DATA['humanoid3d-kd']}` ({len(student.x)} rows, `kd`): both collected with the "
        "paper's protocol (flat, 0-1 m/s, step durations drawn at random, pushes), so a "
        "difference is the controller's. Corr.: correlation of the feature with the label.",
        "",
        "| feature | wbmpc mean (std) | kd mean (std) | KS | corr. wbmpc | corr. kd |",
        "|---|---|---|---|---|---|",
    ]
    shared = []
    for i, name in enumerate(FEATURE_NAMES):
        a, b = teacher.x[:, i], student.x[:, i]
        ks = ks_statistic(a, b)
        if ks <= SHARED_KS:
            shared.append(name)
        lines.append(
            f"| {name} | {a.mean():+.3f} ({a.std():.3f}) | {b.mean():+.3f} ({b.std():.3f}) | "
            f"{ks:.2f} | {np.corrcoef(a, teacher.y)[0, 1]:+.2f} | "
            f"{np.corrcoef(b, student.y)[0, 1]:+.2f} |"
        )
    lines += ["", f"Shared (KS <= {SHARED_KS:g}): `{','.join(shared)}`.", ""]
    return lines


def _plot(loops: dict[str, np.ndarray], datas: dict[str, np.ndarray], path: Path) -> None:
    from gaitnet_mpc.dataset.schema import FEATURE_NAMES
    from gaitnet_mpc.results.plots import new_figure

    fig = new_figure(14.0, 11.0)
    axes = fig.subplots(4, 4).ravel()
    colors = ("tab:red", "tab:blue", "tab:green")
    for i, (ax, name) in enumerate(zip(axes, FEATURE_NAMES, strict=True)):
        for (net, x), color in zip(loops.items(), colors, strict=False):
            both = np.concatenate([datas[net][:, i], x[:, i]])
            bins = np.linspace(*np.percentile(both, [0.5, 99.5]), 40)
            ax.hist(datas[net][:, i], bins=bins, density=True, color=color, alpha=0.25,
                    histtype="stepfilled", label=f"{net}: data")  # fmt: skip
            ax.hist(x[:, i], bins=bins, density=True, color=color, histtype="step",
                    label=f"{net}: loop")  # fmt: skip
        ax.set_title(name, fontsize=8)
        ax.tick_params(labelsize=6)
    axes[0].legend(fontsize=6)
    fig.savefig(path, dpi=90)


if __name__ == "__main__":
    main()
