"""Derivations kept on disk (derivation_cache.py): a model built again in a fresh process
reads them instead of deriving, and gets the same numbers to the bit as a build that
derives everything; a damaged entry is derived again; a Dummy is never stored."""

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import sympy as sp

from mbsynth.symbolic import cache as derivation_cache
from mbsynth.symbolic.cache import fingerprint, remembered

# builds the spatial double pendulum (rigid bodies, revolute joints) in a fresh process and
# prints q̈ at a state off the initial one, the derivations it did and the entries it read
BUILD = textwrap.dedent("""
    import json, sys
    import numpy as np
    import sympy as sp
    from mbsynth.symbolic import cache as derivation_cache
    from mbsynth.symbolic import derive as symbolic
    calls = {"lambdify": 0, "differentiate": 0, "read": 0}
    lambdify, differentiate, loads = sp.lambdify, symbolic.differentiate, derivation_cache.pickle.loads
    def counting(name, f):
        def wrapped(*args, **kwargs):
            calls[name] += name != "lambdify" or bool(args[1])  # not the empty one that gives numpy's names
            return f(*args, **kwargs)
        return wrapped
    sp.lambdify = counting("lambdify", lambdify)
    symbolic.differentiate = counting("differentiate", differentiate)
    derivation_cache.pickle.loads = counting("read", loads)
    import mbsynth as mb
    system = mb.load("models/rigid/double_pendulum_spatial.yaml")
    q, qd = system.initial_state()
    rng = np.random.default_rng(3)
    qdd = system.motion(0.3, q + 0.01 * rng.normal(size=q.size), qd + rng.normal(size=q.size), method="reference").qdd
    print(json.dumps(dict(calls, qdd=[float(x).hex() for x in qdd])))
""")
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def build(cache, **settings):
    env = {**os.environ, "MBSYNTH_CACHE_DIR": str(cache), "MBSYNTH_COMPILED": "off", **settings}
    out = subprocess.run([sys.executable, "-c", BUILD], env=env, cwd=ROOT, capture_output=True, text=True,
                         check=True, timeout=600)
    return json.loads(out.stdout.splitlines()[-1])


def entries(cache):
    return sorted(p for p in cache.glob("derivations/*/*.pkl"))


def test_a_model_built_again_reads_its_derivations_and_gets_the_same_numbers(tmp_path):
    first = build(tmp_path)
    assert first["lambdify"] > 0 and first["differentiate"] > 0 and first["read"] == 0
    assert entries(tmp_path)
    again = build(tmp_path)
    assert again["lambdify"] == 0 and again["differentiate"] == 0 and again["read"] > 0
    derived = build(tmp_path / "other", MBSYNTH_DERIVATION_CACHE="off")
    assert derived["read"] == 0 and not entries(tmp_path / "other")
    assert again["qdd"] == first["qdd"] == derived["qdd"]  # to the bit


def test_a_damaged_entry_is_derived_again_and_rewritten(tmp_path):
    first = build(tmp_path)
    stored = entries(tmp_path)
    for path in stored:
        path.write_bytes(path.read_bytes()[: len(path.read_bytes()) // 2])
    again = build(tmp_path)
    assert again["lambdify"] > 0 and again["qdd"] == first["qdd"]
    assert build(tmp_path)["lambdify"] == 0  # rewritten whole


def test_a_derivation_holding_a_dummy_is_not_stored(tmp_path, monkeypatch):
    monkeypatch.setattr(derivation_cache, "_cache_folder", lambda: tmp_path)
    x, d = sp.Symbol("x"), sp.Dummy("d")
    calls = []
    for _ in range(2):
        assert remembered("test", (x,), lambda: calls.append("stable") or (x**2,)) == (x**2,)
        assert remembered("test", (x + 1,), lambda: calls.append("result") or (d * x,)) == (d * x,)
        assert remembered("test", (d,), lambda: calls.append("inputs") or (x,)) == (x,)
    assert sorted(calls) == ["inputs", "inputs", "result", "result", "stable"]  # read from disk the second time
    assert len(list(tmp_path.glob("test-*.pkl"))) == 1


def test_the_digest_is_the_same_in_every_process_and_tells_numbers_apart():
    expr = "(sp.sin(x) * sp.Rational(3, 7) + sp.Float(0.1) * y**2, sp.Integer(1) * x, 'kind', 3)"
    code = f"import sympy as sp; from mbsynth.symbolic.cache import fingerprint; x, y = sp.symbols('x y'); " \
           f"print(fingerprint({expr}))"
    digests = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                              env={**os.environ, "PYTHONHASHSEED": str(seed)}).stdout.strip() for seed in (1, 2)}
    x, y = sp.symbols("x y")
    assert digests == {fingerprint(eval(expr))}
    assert fingerprint(sp.Float(1.0) * x) != fingerprint(sp.Integer(1) * x)
    assert fingerprint((x, y)) != fingerprint((y, x))
    assert np.unique([fingerprint(sp.Symbol("x", positive=True)), fingerprint(x)]).size == 2


def test_lambdified_code_does_not_depend_on_the_dummies_made_before():
    """lambdify's code for one structure is the same whatever Dummies the process made before
    (a Dummy's name counts them, and a sum's terms are printed in the order of the names), so
    a process that derives it and one that loads it compute with the same rounding."""
    import inspect
    import re

    from mbsynth.symbolic import derive

    x, y, z = (derivation_cache.placeholder(tag) for tag in "xyz")

    def code_after(count):
        """The code, made when the Dummy counter stands at ``count``."""
        while sp.Dummy._count < count:
            sp.Dummy()
        raw = derive._lambdified(None, lambda: ((x, y, z), [x - y + z * y, x * y - z]))
        return re.sub(r"_Dummy_\d+", "_Dummy", inspect.getsource(raw))

    power = 10 ** (len(str(sp.Dummy._count + 10)))
    assert code_after(power - 2) == code_after(power + 100)  # names crossing a digit, then not


# the Andrews squeezer's constraint rows on the compiled path in a fresh process: their
# values at a state off the initial one, and how many tapes it wrote (sympy cse each)
ROWS = textwrap.dedent("""
    import json
    import numpy as np
    from mbsynth.compiled import tape
    written, write = [0], tape.tape
    def counting(*args):
        written[0] += 1
        return write(*args)
    tape.tape = counting
    import mbsynth as mb
    model = mb.load("models/mechanisms/andrews.yaml")
    q, qd = model.initial_state()
    rng = np.random.default_rng(5)
    arrays = model.data("compiled").constraint_arrays(0.3, q + 0.01 * rng.normal(size=q.size), qd, sparse=False)
    print(json.dumps(dict(tapes=written[0], values=[float(x).hex() for x in np.concatenate([np.ravel(arrays.A), arrays.b])])))
""")


def test_a_structure_taped_before_reads_its_tape_and_gets_the_same_numbers(tmp_path):
    """A constraint structure's tape (compiled/structures.py) is kept with the derivations:
    a model loaded again in a fresh process writes none, and its rows are the same to the bit
    as those of a process that writes them all."""
    def rows(cache, **settings):
        env = {**os.environ, "MBSYNTH_CACHE_DIR": str(cache), **settings}
        out = subprocess.run([sys.executable, "-c", ROWS], env=env, cwd=ROOT, capture_output=True, text=True,
                             check=True, timeout=600)
        return json.loads(out.stdout.splitlines()[-1])
    first = rows(tmp_path)
    assert first["tapes"] > 0 and any(p.name.startswith("tape-") for p in entries(tmp_path))
    again = rows(tmp_path)
    assert again["tapes"] == 0
    derived = rows(tmp_path / "other", MBSYNTH_DERIVATION_CACHE="off")
    assert derived["tapes"] == first["tapes"]
    assert again["values"] == first["values"] == derived["values"]
