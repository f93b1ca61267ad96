"""Runs per second of `mbsynth.sweep` on a local Dask cluster with 1 and 2 workers.

    .venv/bin/python benchmarks/sweep_throughput.py [--runs 40]

Each run simulates the paper's example 3 for 1 s (output every 0.02 s). The cluster
is started before timing (its start-up is reported separately). Writes
benchmarks/sweep_results.md. Compare the ratios within one run of this script: the
machines are shared and noisy.
"""

import argparse
import platform
import time
from pathlib import Path

import numpy as np
from distributed import LocalCluster

from mbsynth.studies.sweep import sweep

HERE = Path(__file__).resolve().parent
MODEL = HERE.parent / "models" / "paper" / "example3_two_masses.yaml"


def measure(workers, runs):
    started = time.perf_counter()
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address="127.0.0.1:0") as cluster:
        startup = time.perf_counter() - started
        warm = sweep(MODEL, {"k1": [100.0], "k2": np.linspace(40, 80, workers)}, 0.1,
                     scheduler=cluster.scheduler_address, dt=0.02)  # each worker compiles the model once
        assert (warm["status"] == "ok").all()
        started = time.perf_counter()
        table = sweep(MODEL, {"k1": (40, 160, runs // 4), "k2": (30, 90, 4)}, 1.0,
                      scheduler=cluster.scheduler_address, dt=0.02)
        elapsed = time.perf_counter() - started
    assert (table["status"] == "ok").all()
    return len(table) / elapsed, startup


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=40)
    args = parser.parse_args()
    rows = [(w, *measure(w, args.runs)) for w in (1, 2)]
    base = rows[0][1]
    lines = ["# Sweep throughput", "",
             f"`benchmarks/sweep_throughput.py --runs {args.runs}` on {platform.node()} "
             f"({platform.processor() or platform.machine()}), {time.strftime('%Y-%m-%d')}.", "",
             "| workers | runs/s | speed-up | cluster start-up [s] |", "|---|---|---|---|"]
    lines += [f"| {w} | {rate:.2f} | {rate / base:.2f}× | {startup:.1f} |" for w, rate, startup in rows]
    (HERE / "sweep_results.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
