"""A model is a value; its workspace is a Data; what is kept between calls is in one cache.

Two loads of one file give equal models (``==``, equal hashes, byte-identical motions);
a model cannot be changed after it is made; a Data has its own parameter values and an
explicit path and does not pass for its model; module state lives in ``MEMO`` alone."""

import ast
import dataclasses
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.core.memo import MEMO

ROOT = Path(__file__).resolve().parents[2]
FOUR_BAR = ROOT / "models" / "mechanisms" / "four_bar.yaml"
CANTILEVER = ROOT / "models" / "flexible" / "cantilever.yaml"


@pytest.mark.parametrize("path", [FOUR_BAR, CANTILEVER], ids=lambda p: p.stem)
def test_two_loads_of_one_file_are_equal_and_move_alike(path):
    first, second = mb.load(path), mb.load(path)
    assert first is not second and first.parts[0] is not second.parts[0]
    assert first == second and hash(first) == hash(second)
    assert {first: "model"}[second] == "model"
    q, qd = first.initial_state()
    qd = qd + 0.1
    assert first.motion(0.2, q, qd).qdd.tobytes() == second.motion(0.2, q, qd).qdd.tobytes()


def test_a_model_compares_its_content_once_per_equal_model(monkeypatch):
    """Equal models share their frozen content after one comparison, and a loaded model's
    own methods find its Data without comparing it with the loader's unfinished model (its
    file not yet set): both cost a full content comparison (milliseconds) per call."""
    from mbsynth.core import values
    from mbsynth.model import system as system_module
    first, second = mb.load(FOUR_BAR), mb.load(FOUR_BAR)
    q, qd = first.initial_state()
    assert first == second
    frozen = []
    for module in (values, system_module):
        monkeypatch.setattr(module, "freeze", lambda x: frozen.append(x) or x)
    assert second == first and first == second and second.structure == first.structure
    first.motion(0.0, q, qd), second.motion(0.0, q, qd), second.data()
    assert frozen == []


def test_a_changed_parameter_makes_another_model_and_changing_it_back_the_same():
    model = mb.load(FOUR_BAR)
    name = next(iter(model.parameters))
    heavier = model.with_parameters(**{name: 2 * model.parameters[name] + 1})
    assert heavier != model and heavier.structure == model.structure
    assert heavier.with_parameters(**{name: model.parameters[name]}) == model


def test_another_model_file_is_another_model():
    assert mb.load(FOUR_BAR) != mb.load(ROOT / "models" / "mechanisms" / "slider_crank.yaml")


def test_a_model_cannot_be_changed():
    model = mb.load(FOUR_BAR)
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.name = "other"
    with pytest.raises(ValueError, match="read-only"):
        model.initial_q[0] = 1.0
    with pytest.raises(TypeError):
        model.parameters[next(iter(model.parameters))] = 1.0


def test_a_data_does_not_pass_for_its_model_and_computes_at_its_own_parameters():
    model = mb.load(FOUR_BAR)
    data = model.data()
    assert data.model is model and not hasattr(data, "coordinates") and not hasattr(data, "parts")
    name = next(iter(model.parameters))
    data.set_parameters({name: 3 * model.parameters[name] + 1})
    q, qd = model.initial_state()
    heavier = model.with_parameters(**{name: 3 * model.parameters[name] + 1})
    np.testing.assert_array_equal(data.motion(0.0, q, qd).qdd, heavier.data().motion(0.0, q, qd).qdd)
    assert data.parameter_values[model.parameter_index[name]] != model.parameter_values[model.parameter_index[name]]


def test_the_path_is_chosen_explicitly_and_both_give_the_motion():
    """The compiled path and the KKT path of (2.14) agree (an independent solve); the path
    is the one asked for, whatever has been compiled."""
    model = mb.load(FOUR_BAR)
    kkt, compiled = model.data(path="kkt"), model.data(path="compiled")
    assert (kkt.path, kkt.engine) == ("kkt", None) and compiled.engine is not None
    q, qd = model.initial_state()
    qd = qd + 0.3
    np.testing.assert_allclose(compiled.motion(0.1, q, qd).qdd, kkt.motion(0.1, q, qd).qdd, rtol=1e-9, atol=1e-9)
    with pytest.raises(ValueError, match="path must be one of"):
        model.data(path="fast")


def test_a_state_is_taken_as_given_or_as_an_array_of_n():
    """A state of 1-d contiguous float arrays is used as given (no copy per call); a list,
    a column or a strided view gives the same motion; a wrong size is a ValueError naming
    the shapes."""
    model = mb.load(FOUR_BAR)
    q, qd = model.initial_state()
    qd = qd + 0.3
    assert all(a is b for a, b in zip(model._state(q, qd), (q, qd)))
    wide = np.repeat(np.stack([q, qd]), 2, axis=1)  # q, q̇ as every other entry of a row
    expected = model.motion(0.1, q, qd).qdd
    for given in [(q.tolist(), qd.tolist()), (q[:, None], qd[:, None]), (wide[0, ::2], wide[1, ::2])]:
        np.testing.assert_array_equal(model.motion(0.1, *given).qdd, expected)
    with pytest.raises(ValueError, match=rf"^model 'four_bar' has {model.n} coordinates; got q of shape "
                                         rf"\({model.n - 1},\) and qd of shape \({model.n},\)$"):
        model.motion(0.1, q[1:], qd)



def test_a_read_only_state_is_copied_and_compiles_nothing_more():
    """A model's own ``initial_q`` is read-only (the model is a value): given as the state
    of motion() and motion_batch(), the compiled kernels see a writeable copy, so numba
    compiles no second, read-only specialization of them (a minute on a new machine), and
    the motion equals that of a writeable copy."""
    import numba
    from mbsynth.compiled import kernel, single
    model = mb.from_robot("ur5")
    q, qd = model.initial_q, np.zeros(model.n)
    qd.flags.writeable = False
    assert not q.flags.writeable
    expected = model.motion(0.0, q.copy(), qd.copy()).qdd
    np.testing.assert_array_equal(model.motion(0.0, q, qd).qdd, expected)
    np.testing.assert_array_equal(model.motion_batch(0.0, np.array([q]), np.array([qd]))[0][0], expected)
    q_batch = np.array([q])
    q_batch.flags.writeable = False
    np.testing.assert_array_equal(model.motion_batch(0.0, q_batch, np.array([qd]))[0][0], expected)
    for dispatcher in (kernel.motion_rates, kernel.motion_rows, single.motion_into):
        assert all(argument.mutable for signature in dispatcher.signatures for argument in signature
                   if isinstance(argument, numba.types.Array))

@pytest.mark.parametrize("path", ["compiled", "kkt"])
def test_a_motion_is_of_the_state_it_was_asked_at_whatever_its_arrays_become(path):
    """A Motion's λ and residual are read when first asked for: at the state of the call, not
    at what the caller's arrays hold by then (an integrator's or a controller's own arrays,
    written again at every step). Checked by Qc − C = Aᵀλ at the state of the call."""
    model = mb.from_robot("ur5")
    data = model.data(path)
    q, qd = model.initial_q.copy(), np.linspace(-0.1, 0.1, model.n)
    arrays = data.evaluate(0.0, q.copy(), qd.copy())
    motion = data.motion(0.0, q, qd)
    q += 0.3
    qd *= 2.0
    force = arrays.M @ motion.qdd - arrays.Q - arrays.C
    assert np.abs(arrays.A.T @ motion.lam - force).max() <= 1e-12 * np.abs(force).max()
    assert motion.residual <= 1e-14


def test_the_one_cache_can_be_emptied_without_changing_an_answer():
    model = mb.load(FOUR_BAR)
    q, qd = model.initial_state()
    before = model.motion(0.0, q, qd).qdd
    assert MEMO.sizes()["model structures"] >= 1
    MEMO.clear()
    assert MEMO.sizes()["model structures"] == 0
    np.testing.assert_array_equal(model.motion(0.0, q, qd).qdd, before)


# Module-level state outside MEMO that the package keeps on purpose: the thread pools and
# helper processes (compiled/threads.py, worker.py, ahead.py) and the locks that guard them;
# whether the process froze the model layer's objects (core/collection.py: a fact of the process,
# which MEMO.clear() must not undo).
POOLS = {("compiled/threads.py", "_threads"), ("compiled/threads.py", "_owner"),
         ("compiled/worker.py", "_workers"), ("compiled/ahead.py", "_started"), ("compiled/ahead.py", "_running"),
         ("core/collection.py", "_done")}
MUTATORS = {"append", "extend", "update", "setdefault", "pop", "popitem", "clear", "add", "insert", "remove",
            "discard", "__setitem__"}


def test_no_module_keeps_state_outside_the_one_cache_and_the_pools():
    """No ``global`` statement, and no module-level container written after import, but in
    the pools; what is kept between calls goes in ``MEMO`` (core/memo.py)."""
    found = []
    for path in sorted((ROOT / "mbsynth").rglob("*.py")):
        where = path.relative_to(ROOT / "mbsynth").as_posix()
        tree = ast.parse(path.read_text())
        module_names = {t.id for node in tree.body if isinstance(node, (ast.Assign, ast.AnnAssign))
                        for t in (node.targets if isinstance(node, ast.Assign) else [node.target])
                        if isinstance(t, ast.Name)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Global):
                found += [(where, name) for name in node.names if (where, name) not in POOLS]
            elif isinstance(node, (ast.Assign, ast.AugAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                found += [(where, t.value.id) for t in targets if isinstance(t, ast.Subscript)
                          and isinstance(t.value, ast.Name) and t.value.id in module_names
                          and (where, t.value.id) not in POOLS and _inside_function(tree, node)]
            elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in MUTATORS:
                target = node.func.value
                if isinstance(target, ast.Name) and target.id in module_names and (where, target.id) not in POOLS \
                        and _inside_function(tree, node):
                    found.append((where, target.id))
    assert found == []


def _inside_function(tree, node):
    """Whether ``node`` sits in a function (module-level code builds its tables at import)."""
    return not any(node is inner for top in tree.body if not isinstance(top, (ast.FunctionDef, ast.ClassDef))
                   for inner in ast.walk(top))
