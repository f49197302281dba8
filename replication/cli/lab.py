"""``python -m replication generate-lab``: write the simulated lab's recordings
(:mod:`replication.study.lab`)."""
from __future__ import annotations

import argparse
import time

__all__ = ["add_parser", "run"]


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``generate-lab`` sub-command."""
    gen = sub.add_parser("generate-lab", help="write the simulated lab recordings (default: data/lab)")
    gen.add_argument("--out", help="output folder (default: data/lab of this project)")
    gen.add_argument("--seed", type=int, help="LabSettings.seed (default: that of the committed data)")
    gen.set_defaults(func=run)
    return gen


def run(args: argparse.Namespace) -> int:
    from ..study.lab import LabSettings, default_lab_dir, simulate_lab, write_lab

    start = time.perf_counter()
    settings = LabSettings() if args.seed is None else LabSettings(seed=args.seed)
    out = write_lab(simulate_lab(settings), args.out or default_lab_dir())
    print(f"lab recordings (seed {settings.seed}) written to {out} in {time.perf_counter() - start:.1f} s")
    return 0
