"""``gaitnet-mpc reproduce``: a table or figure of the paper."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

from gaitnet_mpc.experiments.reproduce import FIGURES, REPRODUCIBLE, RESUMABLE

SUMMARY = "reproduce a table or figure of the paper"

#: The humanoid's figures, in order (fig7 ... obstacle).
_FIGURES = tuple(name for name in REPRODUCIBLE if name in FIGURES)
#: The options that only some targets use, and those targets. Their parser default is
#: None, so that one given to a target that does not use it is warned about
#: (:func:`unused_options`, as ``run`` warns); :data:`DEFAULTS` fills them in after.
USED_BY: dict[str, tuple[str, ...]] = {
    "data": ("table1",),
    "overwrite": tuple(name for name in REPRODUCIBLE if name not in RESUMABLE),
    "problems": ("table2",),
    "no_joint_space": ("table2",),
    "quick": ("fig6", *_FIGURES, "all"),
    "no_video": (*_FIGURES, "all"),
    "seeds": ("fig6",),
    "first_seed": ("fig6",),
    "gaitnet_weights": ("fig6",),
    "workers": ("fig6",),
    "backend": ("fig6",),
    "address": ("fig6",),
    "no_progress": ("fig6",),
    "config": ("fig9",),
}
#: The value of each option of :data:`USED_BY` that is not given.
DEFAULTS: dict[str, Any] = {
    "data": Path("data/gaitnet-kd-humanoid3d"),
    "overwrite": False,
    "problems": 40,
    "no_joint_space": False,
    "quick": False,
    "no_video": False,
    "seeds": None,
    "first_seed": 0,
    "gaitnet_weights": None,
    "workers": os.cpu_count() or 1,
    "backend": "process",
    "address": None,
    "no_progress": False,
    "config": None,
}


def add_parser(sub: Any) -> None:
    d = DEFAULTS
    rep = sub.add_parser(
        "reproduce",
        help=SUMMARY,
        description="Reproduce a table or figure of the paper into --out. An option the "
        "chosen table or figure does not use is warned about (its help says which use it).",
    )
    rep.add_argument(
        "what",
        choices=sorted(REPRODUCIBLE),
        help="; ".join(f"{k}: {v}" for k, v in REPRODUCIBLE.items()),
    )
    rep.add_argument("--data", type=Path, help=f"table1: data-set folder (default: {d['data']})")
    rep.add_argument(
        "--out",
        type=Path,
        default=None,
        help="results folder (default: runs/<what>); table2, fig6, fig10 and all resume the "
        "work an interrupted run left in it",
    )
    rep.add_argument(
        "--overwrite",
        action="store_true",
        default=None,
        help=f"{', '.join(USED_BY['overwrite'])} (those that do not resume): replace the "
        "results in an existing --out",
    )
    rep.add_argument(
        "--problems",
        type=int,
        help=f"table2: recorded MPC problems to solve, >= 1 (default: {d['problems']})",
    )
    rep.add_argument(
        "--no-joint-space",
        action="store_true",
        default=None,
        help="table2: skip the explicit KD-SQP and WBD-SQP columns (the slow ones)",
    )
    rep.add_argument(
        "--quick",
        action="store_true",
        default=None,
        help="fig6: one 10 cm layout, 3 s per method; fig7-fig11, obstacle: 2.5-4 s runs "
        "without video, fig10 without its load search; all: every item quick (the test suite's)",
    )
    rep.add_argument(
        "--no-video",
        action="store_true",
        default=None,
        help="fig7-fig11, obstacle, all: no videos",
    )
    rep.add_argument("--seeds", type=int, help="fig6: layouts per gap width (default: 10)")
    rep.add_argument(
        "--first-seed",
        type=int,
        help=f"fig6: the first layout seed (default: {d['first_seed']}, the reported seeds; "
        "tune on >= 100)",
    )
    rep.add_argument(
        "--gaitnet-weights",
        metavar="NAME|PATH",
        help="fig6: Gait-Net's weights, a shipped name, a `gaitnet-mpc train --out DIR` "
        "folder or its DIR/gaitnet.npz (default: the robot's)",
    )
    rep.add_argument(
        "--workers",
        type=int,
        help=f"fig6: cases run in parallel (default: the machine's cores, {d['workers']})",
    )
    rep.add_argument("--backend", choices=("process", "ray"), help=f"fig6: default {d['backend']}")
    rep.add_argument("--address", help="fig6: Ray cluster address (--backend ray)")
    rep.add_argument(
        "--no-progress", action="store_true", default=None, help="fig6: no line per case"
    )
    rep.add_argument(
        "--config",
        type=Path,
        metavar="FILE.toml",
        help="fig9: a settings file for every run (as `gaitnet-mpc run --config`), to "
        "measure an option against the figure's rules",
    )


def unused_options(args: argparse.Namespace) -> list[str]:
    """A warning for each option given that ``args.what`` does not use (as ``run`` warns:
    ``<option> has no effect: <why>``); before :data:`DEFAULTS` fill the options in."""
    what = args.what
    out = []
    for dest, users in USED_BY.items():
        value = getattr(args, dest)
        if value is None or what in users:
            continue
        flag = "--" + dest.replace("_", "-")
        given = flag if isinstance(value, bool) else f"{flag} {value}"
        if dest == "overwrite":
            why = f"reproduce {what} resumes the results in --out, it replaces nothing"
        else:
            why = f"reproduce {what} does not use it (it is for {', '.join(users)})"
        out.append(f"{given} has no effect: {why}")
    if what in USED_BY["no_video"] and args.quick and args.no_video:
        out.append("--no-video has no effect with --quick (quick runs make no video)")
    return out


def main(args: argparse.Namespace) -> int:
    import shlex

    from gaitnet_mpc.experiments import reproduce
    from gaitnet_mpc.results.outdir import check_output_path, folder_lock, write_status

    out = check_output_path(args.out if args.out is not None else Path("runs") / args.what, "--out")
    for text in unused_options(args):
        print(f"gaitnet-mpc: warning: {text}", file=sys.stderr)
    for dest, value in DEFAULTS.items():
        if getattr(args, dest) is None:
            setattr(args, dest, value)
    if args.what == "table2":
        reproduce.check_problems(args.problems)
    elif args.what in ("fig6", "all") or args.what in reproduce.FIGURES:
        pass  # nothing to check before --out
    else:
        from gaitnet_mpc.dataset.check import check_dataset

        check_dataset(args.data)
    command = shlex.join(["gaitnet-mpc", *args.argv])
    if args.what == "fig6":  # holds its own lock and status.json (resumable)
        if out.exists():
            _check_folder(out, args.what, args.overwrite)
        report = reproduce.fig6(
            out,
            quick=args.quick,
            seeds=args.seeds,
            first_seed=args.first_seed,
            gaitnet_weights=args.gaitnet_weights,
            workers=args.workers,
            backend=args.backend,
            address=args.address,
            progress=not args.no_progress,
            command_line=command,
        )
        print(report.read_text(), end="")
        print(f"results in {out}/")
        return 0
    with folder_lock(out, what="reproduce"):
        _check_folder(out, args.what, args.overwrite)
        write_status(out, command=command, state="running", todo=[args.what])
        try:
            if args.what in reproduce.FIGURES:
                report = reproduce.figure(
                    out, args.what, quick=args.quick, video=not args.no_video,
                    config_file=args.config,
                )  # fmt: skip
            elif args.what == "all":
                from gaitnet_mpc.experiments.reproduce_all import reproduce_all

                report = reproduce_all(out, quick=args.quick, video=not args.no_video)
            elif args.what == "table2":
                report = reproduce.table2(
                    out,
                    args.problems,
                    with_joint_space=not args.no_joint_space,
                    progress=lambda n, total: print(
                        f"\rsolved {n}/{total} problems", end="", file=sys.stderr, flush=True
                    ),
                )
                print(file=sys.stderr)
            else:
                report = reproduce.table1(args.data, out)
        except (KeyboardInterrupt, SystemExit):  # SystemExit: a library's SIGTERM handler
            resume = args.what in reproduce.RESUMABLE
            note = "run the same command again to resume" if resume else "run it again"
            write_status(
                out,
                command=command,
                state="interrupted",
                exit_code=130,
                todo=[args.what],
                note=note,
            )
            raise
        except Exception:  # a named error, a crash: the status does not stay running
            write_status(out, command=command, state="failed", todo=[args.what])
            raise
        write_status(out, command=command, state="done", exit_code=0, done=[args.what])
    print(report.read_text(), end="")
    print(f"results in {out}/")
    return 0


def _check_folder(out: Path, what: str, overwrite: bool) -> None:
    """``out`` holds nothing but ``what``'s own files; table1's only with ``overwrite``."""
    from gaitnet_mpc.errors import ConfigError
    from gaitnet_mpc.experiments.reproduce import ARTIFACTS, RESUMABLE
    from gaitnet_mpc.results.outdir import LOCK, STATUS

    names = sorted(p.name for p in out.iterdir() if p.name not in (LOCK, STATUS))
    foreign = [n for n in names if n not in ARTIFACTS[what] and not n.endswith(".part")]
    if foreign:
        raise ConfigError(
            "--out",
            str(out),
            f"a folder of {what} results only (it holds {', '.join(foreign[:4])})",
        )
    if names and what not in RESUMABLE and not overwrite:
        raise ConfigError(
            "--out",
            str(out),
            f"a new or empty folder (it holds {', '.join(names[:4])}); pass --overwrite to "
            "replace the results in it",
        )
