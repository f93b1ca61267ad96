"""A whole robot as parts: load a UR5, decompose it, hang a payload from it, check, validate.

Run it with `.venv/bin/python examples/robot_payload.py` (about a minute: the UR5's joints
are derived symbolically once).

1. models/robots/ur5_payload.yaml: the UR5 of example-robot-data (`type: robot`) — each of
   its 11 links a rigid body in 7 coordinates, the four massless ones (world, base, ee_link,
   tool0) with a zero block of M — and a payload of our own hanging from its flange by a
   spring.
2. `mbsynth check`: M is singular (rank 48 of 84), [M; A] has full column rank, so the
   motion is unique (Result 3).
3. `mbsynth validate`: at random states and joint torques, the joint accelerations equal
   Pinocchio's aba on Pinocchio's own model of the same URDF plus a free-flyer payload.
4. Where Pinocchio fails: a massless link at the end of a chain. aba divides by the zero
   inertia of the leaf and returns NaN; mbsynth names the one indeterminate direction (the
   leaf turning about its joint), says no force acts on it, and that a torque there leaves
   no motion at all.
"""

import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

import mbsynth as mb
from mbsynth.cli.check import format_check
from mbsynth.cli.validate import format_validation
from mbsynth.analysis.diagnose import diagnose
from mbsynth.robots.build import robot_files
from mbsynth.robots.twin import Twin
from mbsynth.robots.validate import sample_pinocchio_state, validate_system

MODEL = Path(__file__).resolve().parent.parent / "models" / "robots" / "ur5_payload.yaml"


def section(title):
    print(f"\n=== {title} ===")


def massless_leaf(folder):
    """example-robot-data's double pendulum with the mass of its last link taken away."""
    tree = ET.parse(robot_files()["double_pendulum"])
    link2 = next(link for link in tree.getroot().findall("link") if link.get("name") == "link2")
    link2.find("inertial/mass").set("value", "0")
    inertia = link2.find("inertial/inertia")
    for key in inertia.attrib:
        inertia.set(key, "0")
    path = Path(folder) / "double_pendulum_massless_leaf.urdf"
    tree.write(path)
    return path


def main():
    section("1. A UR5 decomposed into its links, a payload on a spring")
    started = time.perf_counter()
    system = mb.load(MODEL)
    build_s = time.perf_counter() - started
    q, qd = system.initial_state()
    M = system.evaluate(0.0, q, qd).M
    massless = [p.name for p in system.parts if p.mass == 0]
    print(f"{len(system.parts)} rigid bodies, {system.n} coordinates, {len(system.constraint_names)} constraint rows")
    print("massless links (zero blocks of M):", ", ".join(massless))
    print("rank M =", np.linalg.matrix_rank(M), "of", system.n)
    print("joint torques (parameters):", ", ".join(p for p in system.parameters if p.startswith("tau_")))

    section("2. mbsynth check")
    print(format_check(diagnose(system), MODEL.name).split("  accelerations")[0])

    section("3. mbsynth validate: against Pinocchio's aba")
    print(format_validation([validate_system(system, samples=5, build_s=build_s)], MODEL.name))

    section("4. A massless leaf: Pinocchio returns NaN, mbsynth names the direction")
    with tempfile.TemporaryDirectory() as folder:
        leaf = mb.from_robot(massless_leaf(folder))
        twin = Twin(leaf)
        q, v = sample_pinocchio_state(twin, np.random.default_rng(0))
        with np.errstate(all="ignore"):
            print("pinocchio.aba:", pin.aba(twin.model, twin.data, q, v, np.zeros(twin.model.nv)))
        qm, qdm = twin.to_maximal(q, v)
        print(format_check(diagnose(leaf, q=qm, qd=qdm), "double_pendulum_massless_leaf.urdf").split("  accelerations")[0])
        try:
            leaf.with_parameters(tau_joint2=0.1).motion(0.0, qm, qdm)
        except mb.SolveError as err:
            print("with a torque on joint2:", err)


if __name__ == "__main__":
    main()
