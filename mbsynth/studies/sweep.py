"""Parameter studies on Dask: many simulations of one model, one row of results each.

Every combination of the swept parameters (or every row of a samples table) is one
run: the model with those parameter values simulated to ``t_end``, reduced to the
metrics asked for. Runs go to a Dask cluster — a local one that mbsynth starts
(one single-threaded worker process per core, everything bound to 127.0.0.1) or the
user's (``scheduler``). Each worker builds the model from its text once (file names in
it relative to the model file's folder), with the values it was loaded with and changed
to since (``load(path, parameters=)``, ``with_parameters``: the System the sweep was
given), and reuses it for every run it gets, each run in a Data set to its values
(``Data.set_parameters`` only changes numbers). Results are one table row per
run, failures included with their error; the table is written to ``out`` (.parquet or
.csv) atomically as runs finish and, with every row gathered, when the sweep stops for
any reason (an interruption, a failure), and a sweep restarted with the same ``out``
skips the runs that finished in it (failed ones run again). Runs are keyed by a hash
of their parameter values, so a run that Dask repeats (a worker lost mid-run) still
appears exactly once; every row records the sweep's settings (model and its values,
t_end, simulation options, metrics, the swept parameters and their grid), and a restart with other
settings is refused, naming what changed, rather than mixing the two or dropping rows
(a file that is no sweep's table is refused too). Trajectories come back from the
workers and are written by the client, so ``trajectories`` is a folder on this machine.
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

from ..core.errors import ModelError, SolveError
from ..core.expressions import ExpressionError, parse
from ..core.files import file_format, write_atomically
from ..core.memo import MEMO
from ..core.ranges import parse_range
from ..io import load, loads
from ..analysis.simulate import simulate
from ..model.data import workspace
from ..symbolic.derive import T_SYMBOL
from ..core.tolerances import ELAPSED_FLOOR

log = logging.getLogger(__name__)

AGGREGATES = ("final", "max", "min", "mean")
SUMMARIES = ("energy_drift", "max_residual")
CHECKPOINT_SECONDS = 1.0
LOCALHOST = "127.0.0.1"  # where the local cluster listens: its scheduler, workers and dashboard


@dataclass(frozen=True)
class Metric:
    """A summary of one run: ``energy_drift``, ``max_residual``, or ``AGG:expression``
    with AGG one of final, max, min, mean over the output times and the expression of
    coordinates (``part.coord``), velocities (``part.coord_dot``), joint values
    (``joint.angle``, ``joint.rate``, …), parameters and t."""

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

    def evaluate(self, model, traj):
        """The metric of the run ``traj`` of ``model`` (a System, or a Data: at its parameter values)."""
        data = workspace(model)
        system = data.model
        kind, expr = self.parse(system)
        if expr is None:
            return getattr(traj, kind)
        args = [T_SYMBOL, *system.q_symbols, *system.qd_symbols, *system.parameter_symbols]
        f = sp.lambdify(args, expr, modules="numpy")
        params = [np.full(traj.t.size, v) for v in data.parameter_values]
        values = np.broadcast_to(f(traj.t, *traj.q.T, *traj.qd.T, *params), traj.t.shape)
        return float({"final": lambda v: v[-1], "max": np.max, "min": np.min, "mean": np.mean}[kind](values))


def _symbols(system):
    return system.expression_names()


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


def parse_ranges(texts):
    """['NAME=START:STOP:COUNT', ...] (the --param flags) -> {name: (start, stop, count)};
    a name given twice is refused."""
    ranges = {}
    for text in texts:
        name, spec = parse_range(text)
        if name in ranges:
            raise ModelError(f"--param {name} is given twice ({name}={_axis_text(ranges[name])} and {text!r}): "
                             "give each parameter once")
        ranges[name] = spec
    return ranges


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
    return _digest(json.dumps({k: repr(float(v)) for k, v in sorted(values.items())}))


def _digest(text):
    """16 hex digits of the SHA-1 of ``text``."""
    return hashlib.sha1(text.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class ModelText:
    """What a worker needs to rebuild a System: its file's text, the name errors give,
    the folder its file names (meshes, URDFs) are relative to, the values it was loaded
    with (``load(path, parameters=)``) and the values of its parameters changed since
    (``with_parameters``; those defined by expressions of others follow them), as
    (name, value) pairs."""

    source: str
    name: str
    folder: str
    load_parameters: tuple = ()
    changed: tuple = ()

    @classmethod
    def of(cls, system):
        return cls(system.source, system.name, system.source_folder, tuple(sorted((system.load_parameters or {}).items())),
                   tuple(sorted(changed_parameters(system).items())))

    def system(self):
        """The System as the sweep was given it, the file built once per process."""
        def build():
            system = loads(self.source, name=self.name, folder=self.folder or None, parameters=dict(self.load_parameters))
            return system.with_parameters(**dict(self.changed))
        return _SYSTEMS.get((self.source, self.folder, self.load_parameters, self.changed), build)


SYSTEMS_KEPT = 8  # models a sweep's worker process keeps built (one per model file and load values swept)
_SYSTEMS = MEMO.table("sweep models", SYSTEMS_KEPT)  # (model text, folder, load values, changed values) -> System


def changed_parameters(system):
    """{name: value} of the parameters not defined by expressions of others (``definitions``)
    whose values differ from those ``system`` was built with at load (``with_parameters``)."""
    built, defined = system.built_parameters or {}, system.definitions or {}
    return {name: value for name, value in system.parameters.items()
            if name not in defined and name in built and value != built[name]}


def run_one(model, values, t_end, metrics, options, keep_trajectory=False):
    """One simulation of ``model`` (a ModelText) with ``values``: (a result row, the
    trajectory when ``keep_trajectory`` and the run got one, else None)."""
    row = {"run_id": run_id(values), **values, "status": "ok", "error": ""}
    started = time.perf_counter()
    traj = None
    try:
        data = model.system().data(options.get("path"))
        data.set_parameters(values)  # the sweep's values over the model's
        traj = simulate(data, t_end, **options)
        for metric in metrics:
            row[metric.name] = metric.evaluate(data, traj)
    except Exception as err:  # noqa: BLE001  (every failure is the run's row; the sweep goes on)
        traj = getattr(err, "trajectory", traj)  # a SimulationError's run up to the failure
        row.update(status="failed", error=error_text(err))
        for metric in metrics:
            row[metric.name] = np.nan
    row["wall_time_s"] = time.perf_counter() - started
    row["worker_pid"] = os.getpid()
    return row, traj if keep_trajectory else None


def error_text(err):
    """A failed run's error: the message of a model or solve error (they name the part and
    time), the type and message of any other."""
    if isinstance(err, (SolveError, ModelError, ValueError)):
        return str(err)
    return f"{type(err).__name__}: {err}"


def sweep(model, params=None, t_end=1.0, *, samples=None, metrics=("energy_drift", "max_residual"), out=None,
          scheduler=None, workers=None, trajectories=None, progress=None, **options):
    """Run every combination of ``params`` ({name: (start, stop, count) or values}) or every
    row of ``samples`` (a CSV path or a list of dicts); return the results as a DataFrame.

    model: a model path or a System loaded from a file (its values as loaded, ``parameters=``,
    or changed by ``with_parameters`` kept in every run, the swept ones set over them).
    options: passed to ``simulate`` (dt, method, rtol, atol, stabilization). workers: the
    size of the local cluster (not with ``scheduler``). trajectories: a folder here, where each run's trajectory is saved
    as <run_id>.npz. progress: callable(done, failed, total, eta_s).
    """
    system = model if hasattr(model, "with_parameters") else load(model)
    if not system.source:
        raise ModelError(f"model '{system.name}': a sweep needs a model read from a file (mbsynth.load)")
    if scheduler and workers is not None:
        raise ModelError(f"workers={workers} (--workers) sizes the local cluster mbsynth starts; with the "
                         f"scheduler {scheduler} its own workers run the sweep: give one or the other")
    runs = _runs(system, params, samples)
    if out is not None and file_format(out) not in (".parquet", ".csv"):
        raise ModelError(f"{out}: results must be .parquet or .csv")
    metric_list = [Metric(m) for m in metrics]
    for metric in metric_list:
        metric.parse(system)
    settings = sweep_settings(system, t_end, metric_list, options, params, runs)
    results = _read_results(out, settings)  # failed ones are run again, and kept until then
    todo = [v for v in runs if results.get(run_id(v), {}).get("status") != "ok"]
    log.info("sweep of %d runs: %d already in %s, %d to go", len(runs), len(runs) - len(todo), out, len(todo))
    try:
        if todo:
            if trajectories is not None:
                Path(trajectories).mkdir(parents=True, exist_ok=True)
            with _client(scheduler, workers) as client:
                _execute(client, ModelText.of(system), todo, (t_end, metric_list, options, settings), trajectories,
                         results, out, progress, len(runs))
    finally:  # also on an interruption or a failure: every row gathered is kept
        if out is not None and results:
            _write_results(out, _table(results, runs))
    return _table(results, runs)


def _runs(system, params, samples):
    if (params is None) == (samples is None):
        raise ModelError("give either parameter ranges or samples, not both or neither")
    runs = grid(params) if params is not None else (
        read_samples(samples) if isinstance(samples, (str, Path)) else [dict(s) for s in samples])
    unknown = sorted({k for r in runs for k in r} - set(system.parameters))
    if unknown:
        raise ModelError(f"model '{system.name}' has no parameter(s) {unknown}; it has {sorted(system.parameters)}")
    _refuse_built_parameters(system, sorted({k for r in runs for k in r}))
    return runs


def _refuse_built_parameters(system, swept):
    """A ModelError, before any run, where a swept parameter (or one defined by an expression
    of it) is one the model file built something from at load (``System.fixed_parameters``:
    a flexible body's FE model), naming that file, line and key: a run only changes numbers."""
    fixed, defined = system.fixed_parameters or {}, system.definitions or {}
    for name in swept:
        follows = {name}
        for parameter in system.parameters:  # in order: a definition reads earlier parameters
            if parameter in defined and {str(s) for s in defined[parameter].free_symbols} & follows:
                follows.add(parameter)
        built = sorted(follows & set(fixed))
        if built:
            through = "" if built[0] == name else f" (defined by an expression of the swept '{name}')"
            raise ModelError(f"{fixed[built[0]]}: parameter '{built[0]}'{through} is built into the model when the "
                             f"file is loaded, and a sweep's runs only change numbers: sweep other parameters, or "
                             f"run the model once per value (--set {name}=VALUE)")


class _client:
    """A Dask client on the user's scheduler, or on a local cluster started and stopped here (its
    worker processes, one per core, run the compiled kernels on one thread each: MBSYNTH_THREADS)."""

    def __init__(self, scheduler, workers):
        self.scheduler, self.workers = scheduler, workers

    def __enter__(self):
        from distributed import Client, LocalCluster

        if self.scheduler:
            self.cluster = None
            self.client = Client(self.scheduler)
        else:
            self.cluster = LocalCluster(n_workers=self.workers or os.cpu_count(), threads_per_worker=1,
                                        processes=True, host=LOCALHOST, dashboard_address=f"{LOCALHOST}:0",
                                        silence_logs=logging.ERROR, env={"MBSYNTH_THREADS": "1"})
            self.client = Client(self.cluster)
        return self.client

    def __exit__(self, *exc):
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def _execute(client, model, todo, job, trajectories, results, out, progress, total):
    """Submit the runs ``todo`` (job: t_end, metrics, options, settings) and gather their
    rows into ``results`` as they finish, saving trajectories and checkpoints of ``out``."""
    from distributed import as_completed

    t_end, metrics, options, settings = job
    futures = {client.submit(run_one, model, values, t_end, metrics, options, trajectories is not None,
                             key=f"mbsynth-run-{run_id(values)}", pure=False, retries=2): values
               for values in todo}
    started, last_write = time.perf_counter(), 0.0
    finished = 0
    for future in as_completed(futures):
        row, traj = _outcome(future, futures.pop(future))
        if traj is not None:
            traj.save(Path(trajectories) / f"{row['run_id']}.npz")
        row["settings"] = settings
        results[row["run_id"]] = row
        finished += 1
        if out is not None and time.perf_counter() - last_write > CHECKPOINT_SECONDS:
            _write_results(out, pd.DataFrame(list(results.values())))
            last_write = time.perf_counter()
        if progress is not None:
            rate = finished / max(time.perf_counter() - started, ELAPSED_FLOOR)
            failed = sum(r["status"] != "ok" for r in results.values())
            progress(len(results), failed, total, (total - len(results)) / rate)


def _outcome(future, values):
    """A finished run's (row, trajectory or None); a row of its error when the run never
    returned (a worker lost for good, Dask's own failure)."""
    from distributed import KilledWorker

    try:
        return future.result()
    except KilledWorker as err:
        error = f"worker lost: {err}"
    except Exception as err:  # noqa: BLE001  (the run is recorded as failed, the sweep goes on)
        error = error_text(err)
    return {"run_id": run_id(values), **values, "status": "failed", "error": error}, None


def sweep_settings(system, t_end, metrics, options, params, runs):
    """What a sweep's table holds, as JSON text recorded in every row: the model (its text's
    hash and folder, and where it was loaded with other values or changed since, those:
    ``base``), t_end, the simulation options, the metrics, the swept parameters' names and
    their grid (``grid_text``). A sweep resumed into the table must have the same."""
    settings = {"model_sha1": _digest(system.source), "folder": system.source_folder, "t_end": float(t_end),
                "options": options, "metrics": [m.spec for m in metrics],
                "parameters": sorted({name for values in runs for name in values}),
                "grid": grid_text(params, runs)}
    base = {**(system.load_parameters or {}), **changed_parameters(system)}
    if base:
        settings["base"] = base
    return json.dumps(settings, sort_keys=True, default=list)


def grid_text(params, runs):
    """The runs of a sweep in a few words: 'NAME=START:STOP:COUNT ...' (a list of values:
    'NAME=v1,v2,...', or its length and digest when long) by name, or for samples their
    count and a digest of their values in order."""
    if params is None:
        return f"{len(runs)} samples (sha1 {_digest(json.dumps([run_id(v) for v in runs]))})"
    return " ".join(f"{name}={_axis_text(spec)}" for name, spec in sorted(params.items()))


def _axis_text(spec):
    """One swept parameter's values as given: 'START:STOP:COUNT' or a list of values."""
    if isinstance(spec, tuple) and len(spec) == 3:
        start, stop, count = spec
        return f"{float(start)!r}:{float(stop)!r}:{int(count)}"
    values = [repr(float(v)) for v in np.asarray(spec, dtype=float).ravel()]
    return ",".join(values) if len(values) <= 8 else f"{len(values)} values (sha1 {_digest(','.join(values))})"


def _table(results, runs):
    order = [run_id(v) for v in runs]
    return pd.DataFrame([results[k] for k in order if k in results])


def _read_results(out, settings):
    """The rows of an earlier sweep with the same ``settings`` in ``out`` (by run id); a
    ModelError when ``out`` holds another sweep's runs, or is no sweep's table."""
    if out is None or not Path(out).exists():
        return {}
    table = _read_table(out)
    if not {"run_id", "status"} <= set(table.columns):
        raise ModelError(f"{out}: exists and is not the table of a sweep (it has no run_id and status "
                         f"columns); give another --out, or remove {out}")
    _check_settings(out, set(table["settings"]) if "settings" in table else {""}, settings)
    return {row["run_id"]: row for row in table.to_dict("records")}


def _check_settings(out, found, settings):
    """ModelError unless every row of ``out`` was run with ``settings``, saying what differs."""
    if found <= {settings}:
        return
    now = json.loads(settings)
    other = sorted(found - {settings})[0]
    before = json.loads(other) if other else {}  # "": a table written before settings were recorded
    changes = [f"{key} {before.get(key, 'not recorded')!r} there, {now.get(key, 'not recorded')!r} now"
               for key in sorted(set(now) | (set(before) if before else set())) if before.get(key) != now.get(key)]
    raise ModelError(f"{out}: holds runs of another sweep ({'; '.join(changes)}); resuming would mix them. "
                     f"Give another --out, or remove {out} to start over")


def _read_table(path):
    path = Path(path)
    try:
        table = pd.read_parquet(path) if file_format(path) == ".parquet" else pd.read_csv(path)
    except (OSError, ValueError) as err:
        raise ModelError(f"{path}: cannot read the results of an earlier sweep: {err}") from None
    if "error" in table:
        table["error"] = table["error"].astype(object).fillna("")  # an ok run's empty error (a CSV's empty cell)
    return table


def _write_results(out, table):
    path = Path(out)
    parquet = file_format(path) == ".parquet"
    write_atomically(path, lambda temporary: table.to_parquet(temporary, index=False) if parquet
                     else table.to_csv(temporary, index=False))
