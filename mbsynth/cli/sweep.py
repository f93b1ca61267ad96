"""``mbsynth sweep MODEL --param NAME=START:STOP:COUNT --t-end T --out FILE``: a parameter
study on Dask."""

import json
import sys
import time

from ..studies.sweep import parse_ranges, sweep
from .outputs import Output
from .parsers import check_flags

OUTPUTS = (Output("--out", (".parquet", ".csv"), growing=True), Output("--trajectories", (), growing=True))
from .report import on_terminal


def run(args):
    check_flags(args, positive=("--t-end", "--dt", "--workers"))
    params = parse_ranges(args.param) if args.param else None
    metrics = args.metric or ["energy_drift", "max_residual"]
    options = {} if args.dt is None else {"dt": args.dt}
    bar = _progress if on_terminal(args) else None
    started = time.perf_counter()
    table = sweep(args.model, params, args.t_end, samples=args.samples, metrics=metrics, out=args.out,
                  scheduler=args.scheduler, workers=args.workers, trajectories=args.trajectories,
                  progress=bar, **options)
    if bar:
        sys.stderr.write("\n")
    failed = int((table["status"] != "ok").sum())
    summary = {"runs": len(table), "failed": failed, "out": args.out,
               "wall_time_s": round(time.perf_counter() - started, 3)}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{summary['runs']} runs ({failed} failed) in {summary['wall_time_s']:.3g} s; results in {args.out}")
        for row in table[table["status"] != "ok"].head(5).itertuples():
            print(f"  failed {row.run_id}: {row.error}")
    return 0 if failed == 0 else 1


def _progress(done, failed, total, eta):
    sys.stderr.write(f"\r{done}/{total} runs done, {failed} failed, ~{eta:.0f} s left ")
    sys.stderr.flush()
