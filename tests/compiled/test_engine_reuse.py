"""Engines are reused, freed and chosen once per run (data.py, mbsynth.compiled.background, engine.py).

A System from ``with_parameters`` shares its parent's compiled Template and gets its own
numbers, which must equal those of a Layout built afresh for it, and motions equal to the
literal (2.14) — also when a parameter makes a body massless. Engines die with their
Systems. A run's Data fixes its path when it is made, so runs are bit-identical; a
controller writes parameter values into the run's Data, and no System is built during a run.
"""

import gc
import os
import subprocess
import sys
import textwrap
import weakref
from dataclasses import replace

import numpy as np
import pytest
import sympy as sp

import mbsynth as mb
from mbsynth.core.memo import MEMO
from mbsynth.compiled import background, engine_for
from mbsynth.model.data import shared
from mbsynth.model.system import System
from mbsynth.compiled.layout import build as build_layout

from tests.helpers.compare import rel
from benchmarks import iftomm_reference as ref

# Parameters in a mass, an inertia, frame offsets, a rod's length, gravity and a force.
MODEL = """
name: reuse
parameters: {m: 1.3, L: 0.4, mb: 0.7, Ib: 0.03, R: 0.5, g: 9.81, k: 2.0}
gravity: [0.3, -0.2, -g]
world:
  frames:
    pivot: {position: [0.1, -0.2, 1.5], rpy: [0.3, -0.2, 0.5]}
parts:
  b0: {type: rigid_body, mass: m, inertia: [0.05, 0.04, 0.03], initial: {position: [0.1, -0.2, 1.1]},
       frames: {top: {position: [0, 0, L]}, low: {position: [0.1, 0, -L], rpy: [0.2, 0, 0]}}}
  b1: {type: rigid_body, mass: mb, inertia: [Ib, Ib, 2*Ib], initial: {position: [0.15, -0.25828, 0.48412], rpy: [0.2, 0, 0]},
       frames: {a: {position: [0.05, 0.1, L/2]}}}
  bob: {type: particle, mass: 0.5, initial: {position: [0.4, -0.2, 0.7]}}
joints:
  - {name: pivot, type: spherical, parent: world.pivot, child: b0.top}
  - {name: weld, type: fixed, parent: b0.low, child: b1.a}
  - {name: rod, type: distance, parent: b0, child: bob, length: R}
forces:
  - {name: push, type: force, at: bob, value: ["k*sin(t)", 0, 0]}
"""




@pytest.fixture(scope="module")
def model():
    return mb.loads(MODEL, "reuse")


def a_state(system, seed=3):
    """Random coordinates (unit quaternions) and velocities: (2.14) holds at any state."""
    rng = np.random.default_rng(seed)
    q, qd = rng.standard_normal(system.n), rng.standard_normal(system.n)
    for body in ("b0", "b1"):
        at = system.coordinates.index(f"{body}.qw")
        q[at:at + 4] /= np.linalg.norm(q[at:at + 4])
    return q, qd


def assert_layout_as_built(system, engine):
    """Every array of the Engine's Layout equals that of a Layout built afresh for ``system``."""
    fresh = build_layout(system)[0]
    for field, a, b in zip(fresh._fields, engine.L, fresh):
        assert a.shape == b.shape and np.array_equal(a, b), field


def test_with_parameters_shares_the_compiled_code(model):
    engine = engine_for(model)
    heavier = model.with_parameters(m=2.1, L=0.55, R=0.7, g=3.0, k=-1.0, Ib=0.05)
    derived = engine_for(heavier)  # no wait: nothing to compile
    assert derived is not None and derived is not engine
    assert derived.template is engine.template and derived.module is engine.module
    assert_layout_as_built(heavier, derived)
    for system, fast in ((model, engine), (heavier, derived)):
        q, qd = a_state(system)
        answer = fast.motion(0.5, q, qd)
        assert answer is not None and answer.method == "tree (Baraff)"
        assert rel(answer.qdd, system.motion(0.5, q, qd, method="reference").qdd) < 1e-10
    q, qd = a_state(heavier)
    assert rel(engine.motion(0.5, q, qd).qdd, derived.motion(0.5, q, qd).qdd) > 1e-3  # the numbers differ


def test_a_force_parameter_keeps_the_layout_and_moves_the_motion(model):
    """k enters only the push on the bob (an argument of the generated code), not the
    Layout's numbers (masses, inertias, frames, lengths, gravity: m, L, mb, Ib, R, g): a
    System differing only in k shares its parent's Layout as it is (a controller's torques
    at every sample), and its motion is the literal (2.14)'s with the new k."""
    engine = engine_for(model)
    pushed = model.with_parameters(k=-7.0)
    derived = engine_for(pushed)
    assert {list(model.parameters)[i] for i in engine.template.number_parameters} == {"m", "L", "mb", "Ib", "R", "g"}
    assert derived.L is engine.L
    q, qd = a_state(pushed)
    assert rel(derived.motion(1.0, q, qd).qdd, pushed.motion(1.0, q, qd, method="reference").qdd) < 1e-10
    assert rel(derived.motion(1.0, q, qd).qdd, engine.motion(1.0, q, qd).qdd) > 1e-3  # k does act
    assert engine_for(model.with_parameters(mb=0.9)).L is not engine.L
    # Systems on the shared Layout share its work buffers too (Engine.at): one motion
    # leaves no trace in the other's
    assert derived.buffers is engine.buffers
    assert rel(engine.motion(1.0, q, qd).qdd, model.motion(1.0, q, qd, method="reference").qdd) < 1e-10
    assert rel(derived.motion(1.0, q, qd).qdd, pushed.motion(1.0, q, qd, method="reference").qdd) < 1e-10


def test_parameters_written_into_a_data_give_a_loaded_systems_arrays(model):
    """A controller's values written into a run's Data (``set_parameters``) give the M, Q, A,
    b, C of a System loaded with those values, through the same Evaluator (its groups laid
    out once). Only parts written in a changed parameter are checked again, and a value
    that makes a part's mass matrix indefinite is refused, naming the part."""
    data = model.data()
    q, qd = a_state(model)
    data.evaluate(0.2, q, qd)
    evaluator = data.evaluator
    data.set_parameters({"k": -7.0, "m": 1.1})
    assert data.evaluator is evaluator and data.parameters["m"] == 1.1 and model.parameters["m"] == 1.3
    loaded = mb.loads(MODEL.replace("{m: 1.3,", "{m: 1.1,").replace("k: 2.0}", "k: -7.0}"), "loaded")
    ours, theirs = data.evaluate(0.4, q, qd), loaded.evaluate(0.4, q, qd)
    for name in ("M", "Q", "A", "b", "C"):
        assert rel(getattr(ours, name), getattr(theirs, name)) < 1e-13, name
    assert rel(data.motion(0.4, q, qd).qdd, loaded.motion(0.4, q, qd, method="reference").qdd) < 1e-10
    parts = {p.name: p for p in model.parts}
    m, k = sp.Symbol("m"), sp.Symbol("k")
    assert parts["b0"].reads({m}) and not parts["b1"].reads({m}) and not parts["b0"].reads({k})
    with pytest.raises(mb.ModelError, match="part 'b0': the mass matrix is not positive semi-definite"):
        data.set_parameters({"m": -1.0})
    with pytest.raises(mb.ModelError, match=r"no parameter\(s\) \['mass'\]"):
        data.set_parameters({"mass": 1.0})


@pytest.mark.implementation
def test_the_runs_of_a_system_share_one_evaluation_layout():
    """The Data of each run of a System, and of its ``with_parameters`` children, use one
    Evaluator (its groups laid out once, not once per simulate), each with its own
    parameter values: the arrays equal a fresh load's. The one cache holds it, and nothing
    else once the Systems are gone (``MEMO.clear()`` frees it)."""
    system = mb.loads(MODEL, "reuse")
    first, second = system.data(), system.data()
    q, qd = a_state(system)
    first.constraint_arrays(0.2, q, qd)
    assert second.evaluator is first.evaluator
    child = system.with_parameters(L=0.45)
    run = child.data()
    assert run.evaluator is first.evaluator
    loaded = mb.loads(MODEL.replace("L: 0.4,", "L: 0.45,"), "loaded")
    ours, theirs = run.constraint_arrays(0.3, q, qd, sparse=False), loaded.constraint_arrays(0.3, q, qd, sparse=False)
    for k in range(5):
        assert rel(ours[k], theirs[k]) < 1e-13, k
    made = weakref.ref(first.evaluator)
    del system, first, second, child, run
    gc.collect()
    assert made() is not None  # kept for the next model of this structure
    MEMO.clear()
    gc.collect()
    assert made() is None


@pytest.mark.implementation
def test_a_structural_replace_gets_a_cache_of_its_own(model):
    """``dataclasses.replace`` with other parts or constraints (``with_constraints``) must not
    inherit the compiled Template or Evaluators of another structure; other parameter
    values keep them."""
    assert shared(replace(model, parameters={**model.parameters, "m": 2.0})) is shared(model)
    assert shared(model.with_constraints([])) is shared(model)  # nothing appended: the same structure
    assert shared(replace(model, constraints=model.constraints[:-1])) is not shared(model)
    renamed = {("mass" if k == "m" else k): v for k, v in model.parameters.items()}
    assert shared(replace(model, parameters=renamed)) is not shared(model)


def test_a_massless_body_from_a_parameter(model):
    """b1 welded to b0 loses its mass and inertia: M gets a zero block (a structural change
    of (2.14)'s problem), which the reused Engine meets with the numbers a fresh build has."""
    engine_for(model)
    massless = model.with_parameters(mb=0.0, Ib=0.0)
    derived = engine_for(massless)
    assert derived is not None
    assert_layout_as_built(massless, derived)
    q, qd = a_state(massless)
    arrays = massless.evaluate(0.3, q, qd)
    assert np.linalg.matrix_rank(arrays.M) < massless.n - 2  # b1's six unknowns carry no mass
    ref = massless.motion(0.3, q, qd, method="reference")
    assert ref.unique
    fast = derived.motion(0.3, q, qd)
    assert fast is not None and rel(fast.qdd, ref.qdd) < 1e-10
    assert rel(massless.motion(0.3, q, qd).qdd, ref.qdd) < 1e-10


def test_nothing_but_the_one_cache_holds_systems_and_engines():
    system = mb.loads(MODEL, "reuse")
    child = system.with_parameters(m=3.0)
    engines = [engine_for(system), engine_for(child)]
    assert None not in engines
    refs = [weakref.ref(x) for x in (system, child, *engines, engines[0].template)]
    del system, child, engines
    MEMO.clear()
    gc.collect()
    assert [r() for r in refs] == [None] * len(refs)


def test_a_failed_build_leaves_the_kkt_path_and_holds_no_system(monkeypatch, caplog):
    """A build that raises is logged, its System's motion is the KKT path's ((2.14), the
    reference) and the worker keeps no reference to the System."""
    def broken(system):
        raise RuntimeError("no kernel today")
    monkeypatch.setattr(background, "_build", broken)
    system = mb.loads(MODEL, "broken_build")
    with caplog.at_level("WARNING", logger=background.__name__):
        assert engine_for(system) is None
    assert "no kernel today" in caplog.text and "using the KKT path" in caplog.text
    q, qd = a_state(system)
    assert system.motion(0.0, q, qd).method != "tree (Baraff)"
    ref = weakref.ref(system)
    del system
    MEMO.clear()
    gc.collect()
    assert ref() is None


def test_equal_systems_behave_the_same(model):
    """A second load of the same text is an equal model: it shares the Template and takes
    the same path, with bit-identical motions; a copy with other numbers shares the
    Template (parameters are arguments of its code) with its own numbers."""
    engine = engine_for(model)
    again = mb.loads(MODEL, "reuse")
    theirs = engine_for(again)
    assert again == model and theirs.template is engine.template
    q, qd = a_state(model)
    ours, other = model.data().motion(0.3, q, qd), again.data().motion(0.3, q, qd)
    assert ours.method == other.method == "tree (Baraff)" and np.array_equal(ours.qdd, other.qdd)
    heavier = engine_for(replace(model, parameters={**model.parameters, "m": 5.0}))
    assert heavier.template is engine.template
    assert heavier.L.node_mass[0] == 5.0 and engine.L.node_mass[0] == 1.3


@pytest.mark.implementation
def test_the_runs_of_a_system_share_one_projection():
    """Each run's Data has its own Engine, a copy (``Engine.at``) of the first one made at the
    Layout's parameter values: the projection a run asks for is made once, on that first
    Engine, and every run's is the same (a rigid tree's projection holds no parameter
    values), whichever run asked first and whenever the others' Data were made."""
    system = mb.loads(MODEL, "reuse")
    first, second = system.data().engine, system.data().engine
    origin = first.origin
    assert len({id(first), id(second), id(origin)}) == 3 and second.origin is origin
    made = second.projection()
    assert made is not None and origin.projection() is made and first.projection() is made
    assert system.data().engine.projection() is made


def test_a_parameter_only_the_rows_read_moves_the_projection_too():
    """Two four-bars of one structure, bars of 1 m and 2 m: the Layout has no numbers (the
    rows are all generated), so the second model's Engine is the first's at other parameter
    values (``Engine.at``). The first model's projection made first, the second's projects on
    its own constraints: φ after it is zero to rounding, as the symbolic rows (the KKT
    path's) evaluate it."""
    longer = mb.loads(ref.n_four_bar_yaml(1, L=2.0, g=0.0), name="n_four_bar_1")
    model = mb.loads(ref.n_four_bar_yaml(1, g=0.0), name="n_four_bar_1")
    assert engine_for(longer).projection() is not None
    projection = engine_for(model).projection()
    q, qd = model.initial_state()
    moved = q + 1e-4 * np.sin(np.arange(q.size) + 1.0)
    assert np.abs(model.data(path="kkt").constraint_residuals(0.0, moved, qd)[0]).max() > 1e-6
    projected = projection(0.0, moved, qd)
    assert projected is not None  # the first model's rows: the steps do not converge
    phi, psi = model.data(path="kkt").constraint_residuals(0.0, projected.q, projected.qd)
    assert np.abs(phi).max() < 1e-12 and np.abs(psi).max() < 1e-12


def test_a_data_takes_the_path_it_was_made_with(monkeypatch):
    """The path is the Data's, whatever the cache on disk says: the default path waits for
    the Template though no kernels are marked compiled, a KKT Data never takes the engine,
    and both give (2.14)'s motion."""
    system = mb.loads(MODEL, "reuse")
    monkeypatch.setattr(background, "compiled", lambda: False)
    compiled, kkt = system.data(), system.data(path="kkt")
    assert compiled.engine is not None and kkt.engine is None
    q, qd = a_state(system)
    fast, exact = compiled.motion(0.3, q, qd), kkt.motion(0.3, q, qd)
    assert fast.method == "tree (Baraff)" and exact.method != fast.method
    assert rel(fast.qdd, exact.qdd) < 1e-10


def test_a_controlled_run_builds_no_system(monkeypatch, model):
    """A sampled controller's values go into the run's Data: no System is made after the
    run starts, and the run equals one whose controller's constant value is the model's."""
    made = []
    original = System.__post_init__
    monkeypatch.setattr(System, "__post_init__", lambda self: (made.append(self), original(self)))
    pushed = model.with_parameters(k=-3.0)
    made.clear()
    controlled = mb.simulate(model, 0.2, dt=0.05, controller=lambda t, values: {"k": -3.0}, control_dt=0.05)
    assert made == []
    held = mb.simulate(pushed, 0.2, dt=0.05)
    assert rel(controlled.q, held.q) < 1e-8


RUN = textwrap.dedent("""
    import sys
    import numpy as np
    import mbsynth as mb
    system = mb.loads(sys.argv[1], "reuse").with_parameters(m=1.7)
    traj = mb.simulate(system, 4.0, dt=0.05)
    np.save(sys.argv[2], np.hstack([traj.q, traj.qd]))
""")


def test_runs_are_bit_identical(tmp_path):
    """Two runs of one model in fresh processes, each compiling in the background: 4 s are
    long enough that a run switching paths when its compilation finished (as they did) would
    switch at a different step each time, and differ by about 1e-12."""
    env = {**os.environ, "MBSYNTH_COMPILED": "background"}
    results = []
    for k in range(2):
        out = tmp_path / f"run{k}.npy"
        subprocess.run([sys.executable, "-c", RUN, MODEL, str(out)], env=env, check=True, timeout=900)
        results.append(np.load(out))
    assert results[0].shape == (81, 2 * 17) and np.array_equal(results[0], results[1])
