"""A walk through the paper's example 3: two masses and two springs, built from two parts.

Run it with `make run` (or `.venv/bin/python examples/paper_example3.py`).

Udwadia & Phohomsiri (2006) decompose the system of their figure 2 into two
parts (figure 3), each described in its own coordinates as if it were free,
and join them with one connection constraint. The unconstrained mass matrix (5.33)
is singular, yet the motion is unique: Result 3 says so exactly when [M; A] has
full column rank. When a mass is zero the rank drops, and the missing equation is a
force balance, which mbsynth derives and can append by itself (`balances: auto`).

Each model here has a handful of coordinates: the walk computes on the KKT path of (2.14)
(``system.data(path="kkt")``), which answers at once, instead of compiling the kernels of
the linear-time path first (a few minutes, once per machine).
"""

import shlex
import sys
from pathlib import Path

import numpy as np

import mbsynth as mb
from mbsynth.cli.check import format_check
from mbsynth.analysis.diagnose import diagnose

MODELS = Path(__file__).resolve().parent.parent / "models" / "paper"
OUT = Path(__file__).resolve().parent.parent / "out"
np.set_printoptions(precision=4, suppress=True)
NEXT = [  # what the walk suggests next (its last lines), each a command that runs as printed
    ("check", MODELS / "example3_m2_zero_auto.yaml"),
    ("simulate", MODELS / "example3_two_masses.yaml", "--t-end", "4", "--plot", OUT / "example3.png"),
]


def section(title):
    print(f"\n=== {title} ===")


def main():
    section("1. Two parts joined by q1 = x1 + d (case 5.1, m1, m2 > 0)")
    path = MODELS / "example3_two_masses.yaml"
    system = mb.load(path)
    data = system.data(path="kkt")  # the model's workspace: its parameter values and path
    q, qd = system.initial_state()
    arrays = data.evaluate(0.0, q, qd)
    print("coordinates:", ", ".join(system.coordinates))
    print("M (5.33), singular: rank", np.linalg.matrix_rank(arrays.M), "of", system.n)
    print(arrays.M)
    print("Q (5.34):", arrays.Q, "  A (5.35):", arrays.A, "  b (5.36):", arrays.b)
    print(format_check(diagnose(data), path.name))

    motion = data.motion(0.0, q, qd)
    p = system.parameters
    x1bar, q2bar = q[0] - p["l10"], q[2] - p["l20"]
    a = (-p["k1"] * x1bar + p["k2"] * q2bar) / p["m1"]
    closed_form = np.array([a, a, -a - p["k2"] * q2bar / p["m2"]])
    print("q̈ from (2.15):      ", motion.qdd)
    print("q̈ closed form (5.39):", closed_form)
    print("constraint force Qc = M q̈ − Q:", motion.Qc, " (the spring k2 pulls body 1)")

    section("2. A massless middle node (case 5.2, m1 = 0) without its balance")
    text = path.read_text().replace("m1: 1.5", "m1: 0.0")
    open_model = mb.loads(text, name="example3 with m1 = 0")
    print(format_check(diagnose(open_model.data(path="kkt"), q=[1.06, 1.26, 0.9]), "m1 = 0, as decomposed"))

    section("3. The same with `balances: auto` (models/paper/example3_m1_zero_auto.yaml)")
    path = MODELS / "example3_m1_zero_auto.yaml"
    closed = mb.load(path)
    data = closed.data(path="kkt")
    print(format_check(diagnose(data), path.name))
    q, qd = closed.initial_state()
    p = closed.parameters
    k1, k2, s = p["k1"], p["k2"], (q[0] - p["l10"]) + (q[2] - p["l20"])
    closed_form = np.array([-k1 * k2**2 * s, -k1 * k2**2 * s, -k1**2 * k2 * s]) / (p["m2"] * (k1 + k2) ** 2)
    print("q̈ from (2.15):      ", data.motion(0.0, q, qd).qdd)
    print("q̈ closed form (5.47):", closed_form)

    section("4. The motion of case 5.1, to watch (`mbsynth view`)")
    path = MODELS / "example3_two_masses.yaml"
    system = mb.load(path)
    trajectory = mb.simulate(system, 4.0, dt=1 / 30, path="kkt")
    OUT.mkdir(exist_ok=True)
    page = mb.viewer.to_html(system, trajectory, OUT / "example3.html")
    print(f"simulated 4 s (max constraint residual {trajectory.max_residual:.1e}); the animation plays "
          f"offline in any browser:\n{page}")
    print("\nNext, from this folder: the same report for another example of the paper, and a run with its plot:")
    for words in NEXT:
        print("  " + command(*words))


def command(*words):
    """The command line ``mbsynth WORDS`` as it runs from the current folder: the ``mbsynth``
    program beside this interpreter (``.venv/bin/mbsynth`` under ``make run``), else this
    interpreter with ``-m mbsynth``; paths relative to the current folder where they are in it."""
    program = Path(sys.executable).parent / "mbsynth"
    head = [shown(program)] if program.is_file() else [shown(Path(sys.executable)), "-m", "mbsynth"]
    return shlex.join(head + [shown(word) if isinstance(word, Path) else word for word in words])


def shown(path):
    """``path`` relative to the current folder when it lies inside it, else absolute."""
    path = path.absolute()
    return str(path.relative_to(Path.cwd())) if path.is_relative_to(Path.cwd()) else str(path)


if __name__ == "__main__":
    main()
