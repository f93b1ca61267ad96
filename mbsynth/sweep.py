"""Parameter studies on Dask: many simulations of one model, one row of results each.

Every combination of the swept parameters (or every row of a samples table) is one
run: the model with those parameter values simulated to ``t_end``, reduced to the
metrics asked for. Runs go to a Dask cluster — a local one that mbsynth starts
(one single-threaded worker process per core) or the user's (``scheduler``). Each
worker builds the model from its text once and reuses it for every run it gets
(``System.with_parameters`` only changes numbers). Results are one table row per
run, failures included with their error; the table is written to ``out`` (.parquet or
.csv) atomically as runs finish, and a sweep restarted with the same ``out`` skips
the runs already in it. Runs are keyed by a hash of their parameter values, so a run
that Dask repeats (a worker lost mid-run) still appears exactly once.
"""

import hashlib
import itertools
import json
import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import sympy as sp

from .errors import ModelError, SolveError
from .expressions import ExpressionError, parse
from .io import load, loads
from .simulate import simulate
from .symbolic import T_SYMBOL

log = logging.getLogger(__name__)

AGGREGATES = ("final", "max", "min", "mean")
SUMMARIES = ("energy_drift", "max_residual")
CHECKPOINT_SECONDS = 1.0


@dataclass(frozen=True)
class Metric:
    """A summary of one run: ``energy_drift``, ``max_residual``, or ``AGG:expression``
    with AGG one of final, max, min, mean over the output times and the expression of
    coordinates (``part.coord``), velocities (``part.coord_dot``), parameters and t."""

    spec: str

    @property
    def name(self):
        return self.spec

    def parse(self, system):
        """Check the metric against ``system``; return (aggregate, sympy expression or None)."""
        if self.spec in SUMMARIES:
            return self.spec, None
        kind, sep, text = self.spec.partition(":")
        if not sep or kind not in AGGREGATES:
            raise ModelError(f"metric {self.spec!r}: write {' or '.join(SUMMARIES)}, or AGG:expression "
                             f"with AGG one of {', '.join(AGGREGATES)} (e.g. 'max:body1.x1')")
        try:
            return kind, parse(text, _symbols(system))
        except ExpressionError as err:
            raise ModelError(f"metric {self.spec!r}: {err}") from None

    def evaluate(self, system, traj):
        kind, expr = self.parse(system)
        if expr is None:
            return getattr(traj, kind)
        args = [T_SYMBOL, *system.q_symbols, *system.qd_symbols, *system.parameter_symbols]
        f = sp.lambdify(args, expr, modules="numpy")
        params = [np.full(traj.t.size, v) for v in system.parameters.values()]
        values = np.broadcast_to(f(traj.t, *traj.q.T, *traj.qd.T, *params), traj.t.shape)
        return float({"final": lambda v: v[-1], "max": np.max, "min": np.min, "mean": np.mean}[kind](values))


def _symbols(system):
    table = {str(s): s for s in (*system.q_symbols, *system.qd_symbols, *system.parameter_symbols)}
    table["t"] = T_SYMBOL
    return table


def grid(ranges):
    """All combinations of {name: (start, stop, count)} or {name: [values...]}."""
    axes = {}
    for name, spec in ranges.items():
        if isinstance(spec, tuple) and len(spec) == 3:
            start, stop, count = spec
            if int(count) < 1:
                raise ModelError(f"parameter {name}: COUNT must be at least 1, got {count}")
            axes[name] = np.linspace(float(start), float(stop), int(count))
        else:
            axes[name] = np.asarray(spec, dtype=float).ravel()
    return [dict(zip(axes, map(float, combo))) for combo in itertools.product(*axes.values())]


def parse_range(text):
    """'NAME=START:STOP:COUNT' -> (name, (start, stop, count))."""
    name, sep, spec = text.partition("=")
    parts = spec.split(":")
    try:
        if not sep or len(parts) != 3:
            raise ValueError
        return name.strip(), (float(parts[0]), float(parts[1]), int(parts[2]))
    except ValueError:
        raise ModelError(f"--param {text!r}: expected NAME=START:STOP:COUNT, e.g. k1=10:100:20") from None


def read_samples(path):
    """One run per row of a CSV file whose columns are parameter names."""
    try:
        table = pd.read_csv(path)
    except (OSError, ValueError) as err:
        raise ModelError(f"{path}: cannot read samples: {err}") from None
    if table.empty:
        raise ModelError(f"{path}: no samples")
    bad = [c for c in table.columns if not np.issubdtype(table[c].dtype, np.number)]
    if bad:
        raise ModelError(f"{path}: columns {bad} are not numbers")
    return [{k: float(v) for k, v in row.items()} for row in table.to_dict("records")]


def run_id(values):
    """A stable key of one run's parameter values."""
    text = json.dumps({k: repr(float(v)) for k, v in sorted(values.items())})
    return hashlib.sha1(text.encode()).hexdigest()[:16]


_SYSTEMS = {}  # per worker process: model text hash -> System


def _system(source, name):
    key = hashlib.sha1(source.encode()).hexdigest()
    if key not in _SYSTEMS:
        _SYSTEMS[key] = loads(source, name=name)
    return _SYSTEMS[key]


def run_one(source, name, values, t_end, metrics, options, trajectory_dir=None):
    """One simulation of the model (built once per process) with ``values``: a result row."""
    row = {"run_id": run_id(values), **values, "status": "ok", "error": ""}
    started = time.perf_counter()
    try:
        system = _system(source, name).with_parameters(**values)
        out = None if trajectory_dir is None else Path(trajectory_dir) / f"{row['run_id']}.npz"
        traj = simulate(system, t_end, out=out, **options)
        for metric in metrics:
            row[metric.name] = metric.evaluate(system, traj)
    except (SolveError, ModelError, ValueError) as err:
        row.update(status="failed", error=str(err))
        for metric in metrics:
            row[metric.name] = np.nan
    row["wall_time_s"] = time.perf_counter() - started
    row["worker_pid"] = os.getpid()
    return row


def sweep(model, params=None, t_end=1.0, *, samples=None, metrics=("energy_drift", "max_residual"), out=None,
          scheduler=None, workers=None, trajectories=None, progress=None, **options):
    """Run every combination of ``params`` ({name: (start, stop, count) or values}) or every
    row of ``samples`` (a CSV path or a list of dicts); return the results as a DataFrame.

    model: a model path or a System loaded from a file. options: passed to ``simulate``
    (dt, method, rtol, atol, stabilization). progress: callable(done, failed, total, eta_s).
    """
    system = model if hasattr(model, "with_parameters") else load(model)
    if not system.source:
        raise ModelError(f"model '{system.name}': a sweep needs a model read from a file (mbsynth.load)")
    runs = _runs(system, params, samples)
    if out is not None and Path(out).suffix not in (".parquet", ".csv"):
        raise ModelError(f"{out}: results must be .parquet or .csv")
    metric_list = [Metric(m) for m in metrics]
    for metric in metric_list:
        metric.parse(system)
    done = _read_results(out)
    todo = [v for v in runs if run_id(v) not in done]
    results = dict(done)
    log.info("sweep of %d runs: %d already in %s, %d to go", len(runs), len(done), out, len(todo))
    if todo:
        if trajectories is not None:
            Path(trajectories).mkdir(parents=True, exist_ok=True)
        with _client(scheduler, workers) as client:
            _execute(client, system, todo, t_end, metric_list, options, trajectories, results, out, progress,
                     len(runs))
    table = _table(results, runs)
    if out is not None:
        _write_results(out, table)
    return table


def _runs(system, params, samples):
    if (params is None) == (samples is None):
        raise ModelError("give either parameter ranges or samples, not both or neither")
    runs = grid(params) if params is not None else (
        read_samples(samples) if isinstance(samples, (str, Path)) else [dict(s) for s in samples])
    unknown = sorted({k for r in runs for k in r} - set(system.parameters))
    if unknown:
        raise ModelError(f"model '{system.name}' has no parameter(s) {unknown}; it has {sorted(system.parameters)}")
    return runs


class _client:
    """A Dask client on the user's scheduler, or on a local cluster started and stopped here."""

    def __init__(self, scheduler, workers):
        self.scheduler, self.workers = scheduler, workers

    def __enter__(self):
        from distributed import Client, LocalCluster

        if self.scheduler:
            self.cluster = None
            self.client = Client(self.scheduler)
        else:
            self.cluster = LocalCluster(n_workers=self.workers or os.cpu_count(), threads_per_worker=1,
                                        processes=True, dashboard_address=":0", silence_logs=logging.ERROR)
            self.client = Client(self.cluster)
        return self.client

    def __exit__(self, *exc):
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def _execute(client, system, todo, t_end, metrics, options, trajectories, results, out, progress, total):
    from distributed import as_completed

    futures = {client.submit(run_one, system.source, system.name, values, t_end, metrics, options,
                             None if trajectories is None else str(trajectories), key=f"mbsynth-run-{run_id(values)}",
                             pure=False, retries=2): values
               for values in todo}
    started, last_write = time.perf_counter(), 0.0
    finished = 0
    for future in as_completed(futures):
        try:
            row = future.result()
        except Exception as err:  # a worker lost for good: the run is recorded as failed
            values = futures[future]
            row = {"run_id": run_id(values), **values, "status": "failed", "error": f"worker lost: {err}"}
        results[row["run_id"]] = row
        finished += 1
        if out is not None and time.perf_counter() - last_write > CHECKPOINT_SECONDS:
            _write_results(out, pd.DataFrame(list(results.values())))
            last_write = time.perf_counter()
        if progress is not None:
            rate = finished / max(time.perf_counter() - started, 1e-9)
            failed = sum(r["status"] != "ok" for r in results.values())
            progress(len(results), failed, total, (total - len(results)) / rate)


def _table(results, runs):
    order = [run_id(v) for v in runs]
    return pd.DataFrame([results[k] for k in order if k in results])


def _read_results(out):
    if out is None or not Path(out).exists():
        return {}
    table = _read_table(out)
    return {row["run_id"]: row for row in table.to_dict("records") if row.get("status") == "ok"} \
        if "run_id" in table else {}


def _read_table(path):
    path = Path(path)
    try:
        return pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path, keep_default_na=False)
    except (OSError, ValueError) as err:
        raise ModelError(f"{path}: cannot read the results of an earlier sweep: {err}") from None


def _write_results(out, table):
    path = Path(out)
    tmp = path.with_name(path.name + ".tmp")
    if path.suffix == ".parquet":
        table.to_parquet(tmp, index=False)
    else:
        table.to_csv(tmp, index=False)
    os.replace(tmp, path)
