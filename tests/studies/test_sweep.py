"""Parameter studies on a local two-worker Dask cluster: the natural frequencies of the
paper's example 3 recovered from every run against the exact eigenvalues; a worker
killed mid-sweep; resuming an interrupted sweep, refused when its settings changed;
workers that see other folders than the client; the cluster mbsynth starts listens
on 127.0.0.1 only."""

import importlib
import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from urllib.parse import urlparse

import numpy as np
import pandas as pd
import pytest
import scipy.linalg

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.studies.sweep import _client, grid, run_id, sweep
from mbsynth.analysis.trajectory import load_trajectory

MODEL = Path(__file__).resolve().parents[2] / "models" / "paper" / "example3_two_masses.yaml"
FAST = dict(dt=0.02, rtol=1e-10, atol=1e-12)


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address="127.0.0.1:0") as c:
        yield c


def frequencies_from_samples(x, dt, modes):
    """Angular frequencies of a sum of ``modes`` undamped sinusoids sampled every dt,
    by linear prediction (Prony): x[n] = Σ a_k x[n − k], roots z = exp(±iω dt)."""
    order = 2 * modes
    rows = np.array([x[i:i + order][::-1] for i in range(len(x) - order)])
    a = np.linalg.lstsq(rows, x[order:], rcond=None)[0]
    roots = np.roots(np.concatenate([[1.0], -a]))
    return np.sort(np.abs(np.angle(roots)) / dt)[::2]


def test_grid_is_every_combination():
    runs = grid({"k1": (10, 20, 3), "k2": [1.0, 2.0]})
    assert len(runs) == 6 and {r["k1"] for r in runs} == {10.0, 15.0, 20.0}
    assert len({run_id(r) for r in runs}) == 6


@pytest.mark.slow  # 200 simulations on the cluster
def test_200_runs_recover_the_natural_frequencies(cluster, tmp_path):
    table = sweep(MODEL, {"k1": (40, 160, 10), "k2": (30, 90, 20)}, 1.0, out=tmp_path / "runs.parquet",
                  scheduler=cluster.scheduler_address, trajectories=tmp_path / "traj",
                  metrics=["energy_drift", "max:body1.x1"], **FAST)
    assert len(table) == 200 and (table["status"] == "ok").all()
    assert table["run_id"].is_unique and table["worker_pid"].nunique() == 2  # both workers ran
    system = mb.load(MODEL)
    m1, m2, l10 = system.parameters["m1"], system.parameters["m2"], system.parameters["l10"]
    worst = 0.0
    for row in table.to_dict("records"):
        with np.load(tmp_path / "traj" / f"{row['run_id']}.npz") as data:
            x1bar = data["q"][:, 0] - l10
        K = np.array([[row["k1"] + row["k2"], -row["k2"]], [-row["k2"], row["k2"]]])
        exact = np.sqrt(scipy.linalg.eigh(K, np.diag([m1, m2]), eigvals_only=True))
        found = frequencies_from_samples(x1bar, FAST["dt"], 2)
        worst = max(worst, np.abs(found / exact - 1).max())
        assert row["max:body1.x1"] == pytest.approx(x1bar.max() + l10, rel=1e-12)
    assert worst < 1e-6
    saved = pd.read_parquet(tmp_path / "runs.parquet")
    assert set(saved["run_id"]) == set(table["run_id"])


def test_a_sweep_runs_the_system_it_was_given_with_its_loaded_and_changed_values(cluster, tmp_path):
    """A System loaded with other values (``load(parameters=)``: m2) and changed since
    (``with_parameters``: m1) is swept with them: every run's frequencies are those of its
    own k1, k2 with those masses (not the file's), and the table's settings record them, so
    a sweep of the file as written is not resumed into it."""
    system = mb.load(MODEL, parameters={"m2": 3.0}).with_parameters(m1=0.5)
    out = tmp_path / "runs.csv"
    table = sweep(system, {"k1": [50.0, 120.0]}, 2.0, out=out, scheduler=cluster.scheduler_address,
                  trajectories=tmp_path / "traj", **FAST)
    assert list(table["status"]) == ["ok", "ok"], list(table["error"])
    for row in table.to_dict("records"):
        with np.load(tmp_path / "traj" / f"{row['run_id']}.npz") as data:
            x1bar = data["q"][:, 0] - system.parameters["l10"]
        k2 = system.parameters["k2"]
        K = np.array([[row["k1"] + k2, -k2], [-k2, k2]])
        exact = np.sqrt(scipy.linalg.eigh(K, np.diag([0.5, 3.0]), eigvals_only=True))
        assert np.abs(frequencies_from_samples(x1bar, FAST["dt"], 2) / exact - 1).max() < 1e-6
    assert json.loads(pd.read_csv(out)["settings"][0])["base"] == {"m1": 0.5, "m2": 3.0}
    with pytest.raises(mb.ModelError, match="holds runs of another sweep.*base"):
        sweep(MODEL, {"k1": [50.0, 120.0]}, 2.0, out=out, scheduler=cluster.scheduler_address, **FAST)


@pytest.mark.slow  # 30 runs, a worker process killed midway and started again by its nanny
def test_a_killed_worker_loses_no_run_and_repeats_none(cluster):
    killed = []

    def kill_one_worker(done, failed, total, eta):
        if done == 6 and not killed:
            pid = next(iter(cluster.workers.values())).process.pid  # the worker process under its nanny
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    table = sweep(MODEL, {"k1": (40, 160, 6), "k2": (30, 90, 5)}, 0.5, scheduler=cluster.scheduler_address,
                  progress=kill_one_worker, metrics=["final:body1.x1"], **FAST)
    assert killed
    assert len(table) == 30 and table["run_id"].is_unique and (table["status"] == "ok").all()
    expected = {run_id(r) for r in grid({"k1": (40, 160, 6), "k2": (30, 90, 5)})}
    assert set(table["run_id"]) == expected


def test_an_interrupted_sweep_resumes_without_redoing_finished_runs(cluster, tmp_path):
    out = tmp_path / "runs.csv"
    ranges = {"k1": (40, 160, 3), "k2": (30, 90, 3)}
    first = sweep(MODEL, ranges, 0.5, out=out, scheduler=cluster.scheduler_address, **FAST)
    partial = first.iloc[:4].copy()
    partial["wall_time_s"] = -1.0  # a mark: rows kept from the first sweep are not recomputed
    partial.to_csv(out, index=False)
    resumed = sweep(MODEL, ranges, 0.5, out=out, scheduler=cluster.scheduler_address, **FAST)
    assert len(resumed) == 9 and resumed["run_id"].is_unique
    assert (resumed["wall_time_s"] == -1.0).sum() == 4
    np.testing.assert_allclose(resumed["energy_drift"].astype(float), first["energy_drift"], atol=1e-12)


def test_failed_runs_are_rows_with_their_error(cluster):
    table = sweep(MODEL, {"m1": [1.0, -1.0, 0.0]}, 0.2, scheduler=cluster.scheduler_address, **FAST)
    assert list(table["status"]) == ["ok", "failed", "failed"]
    assert "not positive semi-definite" in table["error"].iloc[1]
    assert "no mass resists" in table["error"].iloc[2]  # m1 = 0 without the balance (5.40)


def test_cli_sweep_with_a_samples_file(cluster, tmp_path, capsys):
    samples = tmp_path / "samples.csv"
    samples.write_text("k1,k2\n50,40\n80,70\n")
    out = tmp_path / "runs.csv"
    code = main(["sweep", str(MODEL), "--samples", str(samples), "--t-end", "0.5", "--dt", "0.05", "--out", str(out),
                 "--scheduler", cluster.scheduler_address, "--metric", "final:body2.q1 + body2.q2", "--json"])
    assert code == 0
    table = pd.read_csv(out)
    assert list(table["k1"]) == [50.0, 80.0] and (table["status"] == "ok").all()


def test_bad_metric_and_unknown_parameter_are_model_errors():
    with pytest.raises(mb.ModelError, match="AGG:expression"):
        sweep(MODEL, {"k1": [1.0]}, 1.0, metrics=["peak:body1.x1"])
    with pytest.raises(mb.ModelError, match="no parameter"):
        sweep(MODEL, {"stiffness": [1.0]}, 1.0)


def test_derived_parameters_and_initial_values_follow_with_parameters():
    system = mb.loads("parameters: {m: 2.0, R: 0.5, Ic: 0.5*m*R**2}\n"
                      "parts:\n  disk: {type: lagrangian, coordinates: [th], T: 0.5*Ic*th_dot**2}\n"
                      "initial: {disk.th_dot: 1/Ic}\n")
    changed = system.with_parameters(m=4.0)
    assert changed.parameters["Ic"] == pytest.approx(0.5) and changed.initial_state()[1][0] == pytest.approx(2.0)
    assert system.parameters["Ic"] == pytest.approx(0.25)  # the original is unchanged


def test_file_names_in_the_model_are_relative_to_its_folder_on_the_workers(cluster, tmp_path, monkeypatch):
    """The workers run in another folder than the model's: its mesh is still found."""
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "body.stl").write_text("solid body\nendsolid body\n")
    model = tmp_path / "body.yaml"
    model.write_text("parameters: {m: 1.0}\nparts:\n  body:\n    type: rigid_body\n    mass: m\n"
                     "    inertia: [1, 1, 1]\n    geometry: {mesh: meshes/body.stl}\n"
                     "initial: {body.x_dot: 1.0}\n")
    monkeypatch.chdir(Path(__file__).parent)
    table = sweep(model, {"m": [1.0, 2.0]}, 0.2, scheduler=cluster.scheduler_address, metrics=["final:body.x"],
                  dt=0.1)
    assert list(table["status"]) == ["ok", "ok"], list(table["error"])
    np.testing.assert_allclose(table["final:body.x"], [0.2, 0.2], rtol=1e-9)  # x = t ẋ(0), no force


@pytest.mark.parametrize("change", ["t_end", "dt", "metric", "model"])
def test_resuming_with_other_settings_is_refused(cluster, tmp_path, change):
    """Rows of a sweep with another t_end, dt, metric list or model file are not mixed in."""
    out = tmp_path / "runs.csv"
    first = dict(t_end=0.5, dt=0.05, metrics=["final:body1.x1"], model=MODEL)
    sweep(first["model"], {"k1": [40.0, 80.0]}, first["t_end"], out=out, metrics=first["metrics"], dt=first["dt"],
          scheduler=cluster.scheduler_address)
    other = tmp_path / "other.yaml"
    other.write_text(MODEL.read_text().replace("k1: 100", "k1: 101"))
    second = dict(first, **{"t_end": dict(t_end=0.4), "dt": dict(dt=0.1), "metric": dict(metrics=["max:body1.x1"]),
                            "model": dict(model=other)}[change])
    with pytest.raises(mb.ModelError, match="holds runs of another sweep.*remove"):
        sweep(second["model"], {"k1": [40.0, 80.0]}, second["t_end"], out=out, metrics=second["metrics"],
              dt=second["dt"], scheduler=cluster.scheduler_address)
    assert len(pd.read_csv(out)) == 2  # the earlier results are untouched


def test_a_changed_setting_is_named_in_the_refusal(cluster, tmp_path):
    out = tmp_path / "runs.parquet"
    sweep(MODEL, {"k1": [40.0]}, 0.5, out=out, scheduler=cluster.scheduler_address, **FAST)
    with pytest.raises(mb.ModelError, match=r"t_end 0\.5 there, 0\.25 now"):
        sweep(MODEL, {"k1": [40.0]}, 0.25, out=out, scheduler=cluster.scheduler_address, **FAST)


def test_a_run_failing_with_another_exception_reports_that_error(monkeypatch):
    """A run that raises something other than a model or solve error (here a RuntimeError
    injected into one run on an in-process worker) is its own failed row, not 'worker lost'."""
    distributed = pytest.importorskip("distributed")
    module = importlib.import_module("mbsynth.studies.sweep")
    real = module.simulate

    def broken_for_k1_80(system, t_end, **options):
        if system.parameters["k1"] == 80.0:
            raise RuntimeError("integrator state corrupted")
        return real(system, t_end, **options)

    monkeypatch.setattr(module, "simulate", broken_for_k1_80)
    with distributed.LocalCluster(n_workers=1, processes=False, dashboard_address=None) as c:
        table = sweep(MODEL, {"k1": [40.0, 80.0]}, 0.2, scheduler=c.scheduler_address, **FAST)
    assert list(table["status"]) == ["ok", "failed"]
    assert table["error"].iloc[1] == "RuntimeError: integrator state corrupted"


def test_trajectories_are_written_by_the_client_in_its_folder(cluster, tmp_path, monkeypatch):
    """--trajectories traj (a relative folder) with a scheduler whose workers run elsewhere:
    every trajectory lands in the client's traj/, the same as the run's metric says."""
    monkeypatch.chdir(tmp_path)
    table = sweep(MODEL, {"k1": [40.0, 80.0]}, 0.5, scheduler=cluster.scheduler_address, trajectories="traj",
                  metrics=["final:body1.x1"], **FAST)
    assert (table["status"] == "ok").all(), list(table["error"])
    for row in table.to_dict("records"):
        saved = load_trajectory(tmp_path / "traj" / f"{row['run_id']}.npz")
        assert saved.status == "completed" and saved.t[-1] == 0.5
        assert saved.column("body1.x1")[-1] == pytest.approx(row["final:body1.x1"], rel=1e-12)


def test_workers_with_a_scheduler_is_an_error(cluster, tmp_path, capsys):
    with pytest.raises(mb.ModelError, match="give one or the other"):
        sweep(MODEL, {"k1": [40.0]}, 0.2, scheduler=cluster.scheduler_address, workers=4)
    code = main(["sweep", str(MODEL), "--param", "k1=40:80:2", "--t-end", "0.2", "--out", str(tmp_path / "o.csv"),
                 "--scheduler", cluster.scheduler_address, "--workers", "4", "--json"])
    assert code == 2 and "--workers" in json.loads(capsys.readouterr().out)["error"]


def listening(psutil):
    """(ip, port) of every socket this process and its children listen on."""
    me = psutil.Process()
    return {(c.laddr.ip, c.laddr.port) for p in (me, *me.children(recursive=True))
            for c in p.net_connections("inet") if c.status == psutil.CONN_LISTEN}


def test_the_local_cluster_listens_on_127_0_0_1_only():
    """The scheduler, the worker and the dashboard of the cluster mbsynth starts: no socket
    on another interface (0.0.0.0 would be every one)."""
    psutil = pytest.importorskip("psutil")
    before = listening(psutil)
    with _client(None, 1) as client:
        opened = listening(psutil) - before
        dashboard = urlparse(client.dashboard_link).port
        scheduler = urlparse(client.scheduler.address).port
    assert {dashboard, scheduler} <= {port for _, port in opened}
    assert {ip for ip, _ in opened} == {"127.0.0.1"}, opened


def test_the_local_clusters_workers_run_the_kernels_on_one_thread_each():
    """One worker process per core, each kernel on one thread (fast/threads.py): the
    workers' threads of the compiled kernels, seen from inside a worker."""
    with _client(None, 2) as client:
        counts = client.run(lambda: __import__("mbsynth.compiled.threads", fromlist=["THREADS"]).THREADS)
    assert sorted(counts.values()) == [1, 1]


def test_a_bad_thread_count_is_refused_by_name():
    done = subprocess.run([sys.executable, "-c", "import mbsynth.compiled.threads"], capture_output=True, text=True,
                          env={**os.environ, "MBSYNTH_THREADS": "two"})
    assert done.returncode != 0 and "MBSYNTH_THREADS must be a positive whole number, got 'two'" in done.stderr


def test_resuming_with_another_swept_parameter_is_refused_naming_it(cluster, tmp_path, capsys, monkeypatch):
    """The user's two commands: a sweep of k1 into x.parquet, then one of k2 into the same
    file. The second is refused (exit 2) naming the parameters and the grid, before any
    run, and the k1 rows stay."""
    monkeypatch.chdir(tmp_path)
    first = ["sweep", str(MODEL), "--param", "k1=40:160:3", "--t-end", "0.5", "--dt", "0.01", "--out", "x.parquet"]
    assert main([*first, "--scheduler", cluster.scheduler_address]) == 0
    capsys.readouterr()
    code = main([*first[:3], "k2=40:160:2", *first[4:], "--workers", "1"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "parameters ['k1'] there, ['k2'] now" in err and "grid 'k1=40.0:160.0:3' there, 'k2=40.0:160.0:2' now" in err
    assert list(pd.read_parquet("x.parquet")["k1"]) == [40.0, 100.0, 160.0]
    with pytest.raises(mb.ModelError, match=r"grid 'k1=40.0:160.0:3' there, 'k1=40.0:160.0:4' now"):  # a finer grid
        sweep(MODEL, {"k1": (40, 160, 4)}, 0.5, out="x.parquet", dt=0.01)
    samples = tmp_path / "samples.csv"
    samples.write_text("k1\n40\n100\n160\n")  # the same runs, given as samples: another grid all the same
    with pytest.raises(mb.ModelError, match=r"grid 'k1=40.0:160.0:3' there, '3 samples \(sha1 [0-9a-f]+\)' now"):
        sweep(MODEL, samples=samples, t_end=0.5, out="x.parquet", dt=0.01)


def test_an_out_file_that_is_no_sweeps_table_is_refused_and_kept(tmp_path):
    out = tmp_path / "mine.csv"
    out.write_text("a,b\n1,2\n")
    with pytest.raises(mb.ModelError, match="is not the table of a sweep"):
        sweep(MODEL, {"k1": [40.0]}, 0.5, out=out, **FAST)
    assert out.read_text() == "a,b\n1,2\n"


def test_a_parameter_given_twice_is_refused(capsys, tmp_path):
    code = main(["sweep", str(MODEL), "--param", "k1=40:160:3", "--param", "k1=10:20:2", "--t-end", "0.5",
                 "--out", str(tmp_path / "o.csv"), "--json"])
    assert code == 2
    assert json.loads(capsys.readouterr().out)["error"] == (
        "--param k1 is given twice (k1=40.0:160.0:3 and 'k1=10:20:2'): give each parameter once")


class InterruptedClient:
    """A cluster that is interrupted (Ctrl-C) while it starts."""

    def __init__(self, *args):
        pass

    def __enter__(self):
        raise KeyboardInterrupt

    def __exit__(self, *exc):
        pass


def test_ctrl_c_before_the_first_run_says_nothing_was_written(tmp_path, capsys, monkeypatch):
    """Interrupted while the cluster starts: exit 130, no file, and the message says so."""
    monkeypatch.setattr(importlib.import_module("mbsynth.studies.sweep"), "_client", InterruptedClient)
    out = tmp_path / "y.parquet"
    code = main(["sweep", str(MODEL), "--param", "k1=40:160:3", "--t-end", "0.5", "--out", str(out)])
    assert code == 130 and capsys.readouterr().err == f"error: interrupted; nothing was written to {out}\n"
    assert not out.exists()


@pytest.mark.parametrize("stop", [KeyboardInterrupt, RuntimeError])
def test_a_sweep_stopped_midway_keeps_every_row_gathered(cluster, tmp_path, capsys, monkeypatch, stop):
    """Ctrl-C (exit 130) or a failure (a bug: exit 3) after the second run: both rows are in
    the table (the checkpoint every second would have kept at most the first), and
    resuming runs only the rest."""
    module = importlib.import_module("mbsynth.studies.sweep")
    monkeypatch.setattr(module, "CHECKPOINT_SECONDS", 1e9)
    out = tmp_path / "y.csv"
    line = ["sweep", str(MODEL), "--param", "k1=40:160:4", "--t-end", "0.2", "--dt", "0.05", "--out", str(out),
            "--scheduler", cluster.scheduler_address]
    real = module._execute

    def stopping(client, model, todo, job, trajectories, results, out_, progress, total):
        def after_two(done, failed, total_, eta):
            if done == 2:
                raise stop("stopped")
        return real(client, model, todo, job, trajectories, results, out_, after_two, total)

    monkeypatch.setattr(module, "_execute", stopping)
    code = main(line)
    err = capsys.readouterr().err
    assert code == (130 if stop is KeyboardInterrupt else 3), err
    if stop is KeyboardInterrupt:
        assert err == f"error: interrupted; the output so far is in {out}\n"
    kept = pd.read_csv(out)
    assert len(kept) == 2 and (kept["status"] == "ok").all()
    monkeypatch.setattr(module, "_execute", real)
    assert main(line) == 0
    resumed = pd.read_csv(out).set_index("run_id")
    assert len(resumed) == 4  # the two kept rows as they were (not run again), two new ones
    assert list(resumed.loc[kept["run_id"], "wall_time_s"]) == list(kept["wall_time_s"])


def test_failed_rows_are_kept_until_run_again(cluster, tmp_path, monkeypatch):
    """A resumed sweep runs its failed runs again; interrupted before they finish, the table
    still holds their rows with the error."""
    out = tmp_path / "runs.csv"
    sweep(MODEL, {"m1": [1.0, -1.0]}, 0.2, out=out, scheduler=cluster.scheduler_address, **FAST)

    monkeypatch.setattr(importlib.import_module("mbsynth.studies.sweep"), "_client", InterruptedClient)
    with pytest.raises(KeyboardInterrupt):
        sweep(MODEL, {"m1": [1.0, -1.0]}, 0.2, out=out, scheduler=cluster.scheduler_address, **FAST)
    kept = pd.read_csv(out)
    assert list(kept["status"]) == ["ok", "failed"] and "not positive semi-definite" in kept["error"].iloc[1]


FLEXIBLE_ROD = """\
name: rod
parameters: {L: 1.0, I0: 1.0e-9, Iy: 2*I0, g: 9.81}
gravity: [0, 0, -g]
parts:
  rod:
    type: flexible_body
    beam: {length: L, elements: 4, area: 1e-4, Iy: Iy, Iz: 1e-9, J: 2e-9, E: 2e8, nu: 0.3, density: 1000}
    reduction: {method: craig_bampton, interface: [0], modes: 1}
"""


@pytest.mark.parametrize("param, words", [
    ("L=1:2:3", ":7, key parts.rod.beam.length: parameter 'L' is built into the model"),
    ("I0=1e-9:2e-9:3", ":7, key parts.rod.beam.Iy: parameter 'Iy' (defined by an expression of the swept 'I0')"),
])
def test_sweeping_a_parameter_the_fe_model_is_built_from_is_refused_before_any_run(tmp_path, param, words):
    """``mbsynth sweep`` of the beam's length (or of a parameter another one the beam reads is
    defined by): exit 2 before the cluster starts, naming the model file, the line and the key
    of the beam that reads it; no results file."""
    path = tmp_path / "rod.yaml"
    path.write_text(FLEXIBLE_ROD)
    out = tmp_path / "o.csv"
    result = subprocess.run([sys.executable, "-m", "mbsynth.cli", "sweep", str(path), "--param", param, "--t-end",
                             "0.1", "--out", str(out), "--workers", "1"], capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert result.stderr.startswith(f"error: {path}:7, key ") and words in result.stderr, result.stderr
    assert "--set" in result.stderr and not out.exists()
