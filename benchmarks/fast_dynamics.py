"""The compiled path (mbsynth.compiled) against Pinocchio's ``aba`` on the same systems, in one process.

    .venv/bin/python benchmarks/fast_dynamics.py [--quick]

Per evaluation of ``System.motion`` (assembly + solve, the Motion object included) and of
``pinocchio.aba`` (both called from Python): spatial pendulum chains of N = 1, 10, 100,
1000 rigid links on revolute joints whose axes alternate between x and y, and the robots
ur5, panda, solo12 (floating) and talos (floating) from example-robot-data
(``mbsynth.robots.build.from_robot``; Pinocchio reads the same URDF). Each state is drawn in
Pinocchio's coordinates and mapped to mbsynth's by forward kinematics, and the two
accelerations are compared (the links' angular accelerations, world axes) — the same
system, not just the same size. Also: the growth exponent from N = 100 to 1000, the
batched per-state time for 1024 states (``System.motion_batch``), the dense paths (KKT and
the literal pseudo-inverse of (2.14)), peak memory for N = 1000, the start-up of
``mbsynth check`` and the compile times of the kernels with a cold and a warm cache.
Writes benchmarks/fast_results.md. Ratios are
within one run of this script: the machines are shared and noisy, so every time is the
best of several repeats, and motion() and aba are timed in alternating rounds.
"""

import argparse
import datetime
import os
import platform
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pinocchio as pin

import mbsynth as mb
from mbsynth.robots import build as robots
from mbsynth.core import solvers
from mbsynth.compiled import engine_for
from mbsynth.core.kinematics import matrix_quaternion

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
LENGTH, MASS = 0.5, 1.0
ROBOTS = [("ur5", False), ("panda", False), ("solo12", True), ("talos", True)]
# Pinocchio's createData for a chain of 1000 joints asks for more than 22 GiB (the process is
# killed on this 24 GiB machine; under `ulimit -v 8000000` it raises MemoryError)
PINOCCHIO_MAX_CHAIN = 100
ROUNDS = 5  # motion() and aba are timed in alternating rounds; each keeps its best
BATCH_ROUNDS = 9  # motion_batch and aba: the median of alternating rounds


# ----------------------------------------------------------------------------- the chain

def axis(i):
    return [1, 0, 0] if i % 2 == 0 else [0, 1, 0]


def chain_yaml(count):
    """N links of length LENGTH hanging from the world, revolute joints about x, y, x, ..."""
    lines = [f"name: chain_{count}", f"parameters: {{m: {MASS}, L: {LENGTH}}}", "gravity: [0, 0, -9.81]",
             f"world: {{frames: {{pivot: {{position: [0, 0, 0], axis: {axis(0)}}}}}}}", "parts:"]
    for i in range(count):
        lines.append(f"  link{i}: {{type: rigid_body, mass: m, inertia: [m*L**2/12, m*L**2/12, m*L**2/40], "
                     f"frames: {{top: {{position: [0, 0, L/2], axis: {axis(i)}}}, "
                     f"bottom: {{position: [0, 0, -L/2], axis: {axis(i + 1)}}}}}, "
                     f"initial: {{position: [0, 0, {-(i + 0.5) * LENGTH}]}}}}")
    lines.append("joints:")
    for i in range(count):
        parent = "world.pivot" if i == 0 else f"link{i - 1}.bottom"
        lines.append(f"  - {{name: j{i}, type: revolute, parent: {parent}, child: link{i}.top}}")
    return "\n".join(lines) + "\n"


class PinocchioChain:
    """The same chain in Pinocchio: joint i at the top of link i, about x or y of the
    link's axes; the state map by forward kinematics."""

    def __init__(self, count):
        self.model = pin.Model()
        parent = 0
        inertia = pin.Inertia(MASS, np.array([0, 0, -LENGTH / 2]),
                              np.diag([MASS * LENGTH**2 / 12, MASS * LENGTH**2 / 12, MASS * LENGTH**2 / 40]))
        for i in range(count):
            joint = pin.JointModelRX() if i % 2 == 0 else pin.JointModelRY()
            placement = pin.SE3(np.eye(3), np.array([0, 0, 0 if i == 0 else -LENGTH]))
            parent = self.model.addJoint(parent, joint, placement, f"j{i}")
            self.model.appendBodyToJoint(parent, inertia, pin.SE3.Identity())
        self.data = self.model.createData()

    def to_maximal(self, q, v):
        pin.forwardKinematics(self.model, self.data, q, v)
        qm, qdm = [], []
        c = np.array([0, 0, -LENGTH / 2])
        for i in range(1, self.model.njoints):
            R, p = self.data.oMi[i].rotation, self.data.oMi[i].translation
            u = matrix_quaternion(R)
            omega = R @ self.data.v[i].angular
            G = np.column_stack([-u[1:], u[0] * np.eye(3) + pin.skew(u[1:])])
            qm += [*(p + R @ c), *u]
            qdm += [*(R @ (self.data.v[i].linear + np.cross(self.data.v[i].angular, c))), *(G.T @ omega / 2)]
        return np.array(qm), np.array(qdm)

    def angular_accelerations(self, q, v, a):
        pin.forwardKinematics(self.model, self.data, q, v, a)
        return np.array([self.data.oMi[i].rotation @ self.data.a[i].angular for i in range(1, self.model.njoints)])


def rotation_about(axis_index, angle):
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0)][axis_index]  # about x: the (y, z) plane; about y: (z, x)
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def chain_to_maximal(q, v):
    """PinocchioChain.to_maximal by forward kinematics in numpy, for chains longer than
    PINOCCHIO_MAX_CHAIN (equal to it within 1e-15 at N = 10)."""
    R, p, omega, pdot = np.eye(3), np.zeros(3), np.zeros(3), np.zeros(3)
    down, half = np.array([0, 0, -LENGTH]), np.array([0, 0, -LENGTH / 2])
    qm, qdm = [], []
    for i, (angle, rate) in enumerate(zip(q, v)):
        if i:
            pdot = pdot + np.cross(omega, R @ down)
            p = p + R @ down
        R = R @ rotation_about(i % 2, angle)
        omega = omega + R[:, i % 2] * rate
        u = matrix_quaternion(R)
        G = np.column_stack([-u[1:], u[0] * np.eye(3) + pin.skew(u[1:])])
        qm += [*(p + R @ half), *u]
        qdm += [*(pdot + np.cross(omega, R @ half)), *(G.T @ omega / 2)]
    return np.array(qm), np.array(qdm)


def mbsynth_angular_accelerations(q, qdd):
    """ω̇ = 2 G(u) ü per rigid body (world axes), from maximal q, q̈ (7 per body)."""
    out = []
    for u, udd in zip(q.reshape(-1, 7)[:, 3:], qdd.reshape(-1, 7)[:, 3:]):
        G = np.column_stack([-u[1:], u[0] * np.eye(3) + pin.skew(u[1:])])
        out.append(2 * G @ udd)
    return np.array(out)


# ----------------------------------------------------------------------------- timing

def best(fn, seconds=0.4, repeats=5):
    """Best mean time of one call over ``repeats`` batches (each about ``seconds`` / repeats)."""
    fn()
    started = time.perf_counter()
    fn()
    once = max(time.perf_counter() - started, 1e-7)
    count = max(1, int(seconds / repeats / once))
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        for _ in range(count):
            fn()
        times.append((time.perf_counter() - started) / count)
    return min(times)


def dense_kkt(system, q, qd):
    a = system.evaluate(0.0, q, qd)
    return solvers.kkt_acceleration(a.M, a.Q, a.A, a.b, a.C)


class Case:
    """One system in both libraries: its mbsynth System, Pinocchio (model, data), states."""

    def __init__(self, label, system, model, to_maximal, angular, draw, loaded_s):
        self.label, self.system, self.model = label, system, model
        self.data = None if model is None else model.createData()
        self.to_maximal, self.angular, self.draw, self.loaded_s = to_maximal, angular, draw, loaded_s

    def run(self, rng, dense=True):
        system = self.system
        started = time.perf_counter()
        engine = engine_for(system)
        build_s = time.perf_counter() - started
        q, v = self.draw(rng)
        qm, qdm = self.to_maximal(q, v)
        motion = system.motion(0.0, qm, qdm)
        assert motion.method == "tree (Baraff)", motion.method
        row = dict(label=self.label, bodies=len(engine.L.node_kind), n=system.n, nv=len(v), loaded_s=self.loaded_s,
                   build_s=build_s, fast=float("inf"), aba=float("nan"), error=float("nan"))
        if self.model is not None:
            tau = np.zeros(self.model.nv)
            a = pin.aba(self.model, self.data, q, v, tau)
            error = np.abs(mbsynth_angular_accelerations(qm, motion.qdd) - self.angular(q, v, a)).max()
            row.update(error=error / max(1.0, np.abs(a).max()), aba=float("inf"))
        for _ in range(ROUNDS):  # alternating, so that a burst of load on the machine hits both alike
            row["fast"] = min(row["fast"], best(lambda: system.motion(0.0, qm, qdm), seconds=0.2))
            if self.model is not None:
                row["aba"] = min(row["aba"], best(lambda: pin.aba(self.model, self.data, q, v, tau), seconds=0.2))
        if dense:
            row["kkt"] = best(lambda: dense_kkt(system, qm, qdm), seconds=0.5, repeats=2)
            row["pinv"] = best(lambda: system.motion(0.0, qm, qdm, method="reference"), seconds=0.5, repeats=2)
        return row

    def batch(self, rng, count=1024):
        """(per-state time of System.motion_batch over ``count`` states, aba's time): the
        medians of BATCH_ROUNDS alternating rounds (benchmarks/motion_batch.py): the batch
        needs every core, so load from other tenants shows in it first."""
        from motion_batch import batch_rounds
        return tuple(np.median(batch_rounds(self, rng, count, BATCH_ROUNDS), axis=0))


def chain_case(count):
    started = time.perf_counter()
    system = mb.loads(chain_yaml(count), name=f"chain_{count}")
    loaded = time.perf_counter() - started

    def draw(rng):
        return rng.uniform(-1, 1, count), rng.normal(size=count)
    if count > PINOCCHIO_MAX_CHAIN:  # mbsynth alone: no aba to compare with
        return Case(f"chain N = {count}", system, None, chain_to_maximal, None, draw, loaded)
    chain = PinocchioChain(count)
    return Case(f"chain N = {count}", system, chain.model, chain.to_maximal, chain.angular_accelerations, draw,
                loaded)


def robot_case(name, floating):
    from mbsynth.robots.twin import Twin
    from mbsynth.robots.validate import sample_pinocchio_state
    started = time.perf_counter()
    system = robots.from_robot(name, floating=floating)
    loaded = time.perf_counter() - started
    twin = Twin(system)

    def angular(q, v, a):
        pin.forwardKinematics(twin.model, twin.data, q, v, a)
        out = []
        for part in system.parts:
            placed = twin.bodies[part.name]
            R = twin.data.oMi[placed.joint].rotation
            out.append(R @ twin.data.a[placed.joint].angular)  # a body's ω̇ is its joint's
        return np.array(out)
    return Case(f"{name}{' (floating)' if floating else ''}", system, twin.model, twin.to_maximal, angular,
                lambda rng: sample_pinocchio_state(twin, rng), loaded)


# ----------------------------------------------------------------------------- the rest

def peak_memory(case):
    """Peak traced allocation (MiB) of building an Engine (layout, buffers; kernels cached)
    and one motion()."""
    from mbsynth.compiled.engine import Engine
    q, qd = case.system.initial_state()
    tracemalloc.start()
    Engine.build(case.system).motion(0.0, q, qd)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak / 2**20


def startup(cache):
    """Wall time of ``mbsynth check`` on a paper model with the cache directory ``cache``."""
    env = dict(os.environ, MBSYNTH_CACHE_DIR=str(cache))
    env.pop("NUMBA_CACHE_DIR", None)
    command = [str(ROOT / ".venv" / "bin" / "mbsynth"), "check", str(ROOT / "models/paper/example1_wheel.yaml")]
    started = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True, env=env)
    return time.perf_counter() - started


def compile_times(cache):
    """Seconds to build a first Engine (double pendulum) in a fresh process: (cold, warm)."""
    code = ("import time, mbsynth as mb\nfrom mbsynth.compiled import engine_for\n"
            "s = mb.load('models/rigid/double_pendulum_spatial.yaml')\nt = time.perf_counter()\n"
            "engine_for(s)\nprint(time.perf_counter() - t)\n")
    env = dict(os.environ, MBSYNTH_CACHE_DIR=str(cache))
    env.pop("NUMBA_CACHE_DIR", None)
    run = [sys.executable, "-c", code]
    return [float(subprocess.run(run, check=True, capture_output=True, text=True, env=env, cwd=ROOT).stdout)
            for _ in range(2)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="chains up to N = 100 and ur5 only")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as cache:
        startups = startup(cache), startup(cache)
        compiled = compile_times(Path(cache) / "compile")
    rows, batch, memory = [], {}, None
    for name, floating in ROBOTS[:1] if args.quick else ROBOTS:
        case = robot_case(name, floating)
        rows.append(case.run(rng))
        if name in ("ur5", "talos"):
            batch[rows[-1]["label"]] = case.batch(rng)
        write(rows, batch, startups, compiled, memory)  # as it goes: the largest chain takes long to load
    check = PinocchioChain(10), rng.uniform(-1, 1, 10), rng.normal(size=10)
    for mine, theirs in zip(chain_to_maximal(*check[1:]), check[0].to_maximal(*check[1:])):
        assert np.abs(mine - theirs).max() < 1e-14, "chain_to_maximal must agree with Pinocchio's kinematics"
    for count in [1, 10, 100] if args.quick else [1, 10, 100, 1000]:
        case = chain_case(count)
        rows.append(case.run(rng, dense=count <= 100))
        memory = (count, peak_memory(case))
        write(rows, batch, startups, compiled, memory)


def exponent(rows):
    by = {r["bodies"]: r["fast"] for r in rows if r["label"].startswith("chain")}
    if 100 in by and 1000 in by:
        return np.log(by[1000] / by[100]) / np.log(10)
    return float("nan")


def us(seconds):
    return f"{seconds * 1e6:,.1f}"


def write(rows, batch, startups, compiled, memory):
    lines = ["# mbsynth.compiled against Pinocchio", "",
             f"{datetime.date.today()}, {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
             f"Python {platform.python_version()}, Pinocchio {pin.__version__}; written by "
             "`benchmarks/fast_dynamics.py` (best of several repeats, motion() and aba in alternating rounds; ratios within this run).", "",
             "Per evaluation, called from Python: `System.motion` (assembly + solve, tree path) and "
             "`pinocchio.aba`; the dense paths are `System.evaluate` + KKT (`solvers.kkt_acceleration`) "
             "and the literal pseudo-inverse of (2.14) (`method=\"reference\"`). *agree*: largest "
             "difference of the links' angular accelerations, relative to the largest joint acceleration.", "",
             "| system | bodies | n | nv | motion() µs | aba µs | ratio | dense KKT µs | pinv (2.14) µs | agree |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if np.isfinite(r["aba"]):
            aba, ratio, agree = us(r["aba"]), f"{r['fast'] / r['aba']:.1f}", f"{r['error']:.1e}"
        else:
            aba, ratio, agree = "—*", "—", "—"
        lines.append(f"| {r['label']} | {r['bodies']} | {r['n']} | {r['nv']} | {us(r['fast'])} | {aba} | {ratio} | "
                     f"{us(r['kkt']) if 'kkt' in r else '—'} | {us(r['pinv']) if 'pinv' in r else '—'} | {agree} |")
    if not all(np.isfinite(r["aba"]) for r in rows):
        lines += ["", "\\* Pinocchio's `createData` for this chain asks for more than 22 GiB (the process is "
                  "killed on this 24 GiB machine), so there is no `aba` to compare with; mbsynth's state comes "
                  "from forward kinematics in numpy (`chain_to_maximal`)."]
    lines += ["", f"Growth exponent of motion() from N = 100 to 1000: **{exponent(rows):.2f}**.", ""]
    if batch:
        lines += ["Batched, 1024 states (`System.motion_batch`: one thread per core, taking chunks of rows in turn; "
                  f"aba timed in alternating rounds with it, the median of {BATCH_ROUNDS} rounds each; the spread "
                  "over rounds: benchmarks/motion_batch.py):", "",
                  "| system | per state µs | aba µs | ratio |", "|---|---:|---:|---:|"]
        lines += [f"| {label} | {us(t)} | {us(a)} | {t / a:.1f} |" for label, (t, a) in batch.items()]
        lines.append("")
    if memory:
        count, mib = memory
        lines += [f"Peak traced memory of building the compiled path (layout, buffers) and one motion() for the "
                  f"chain of N = {count}: {mib:.1f} MiB (the dense KKT matrix alone would take "
                  f"{(7 * count + 6 * count) ** 2 * 8 / 2**20:,.0f} MiB).", ""]
    lines += [f"`mbsynth check models/paper/example1_wheel.yaml`: {startups[0]:.2f} s with an empty cache, "
              f"{startups[1]:.2f} s warm (it never compiles: it uses (2.14)).", "",
              f"Building a first Engine in a fresh process: {compiled[0]:.1f} s with a cold cache (numba compiles), "
              f"{compiled[1]:.2f} s warm. Until then System.motion uses the KKT path (background.py).", ""]
    (HERE / "fast_results.md").write_text("\n".join(lines))
    print(rows[-1], flush=True)


if __name__ == "__main__":
    main()
