"""Symbolic derivations kept on disk, so that a model built again in a fresh process
skips sympy's differentiation and code generation (the in-process caches of derive.py and
model/joint_templates.py hold them only for the process).

``remembered(kind, inputs, derive)`` returns ``derive()``, stored under a digest of
``kind``, ``inputs`` (nested tuples of sympy expressions, strings and numbers), this
package's sources, sympy's version and Python's bytecode version (compiled functions are
kept as code: ``remembered_function``): any change of the code that derives them makes a
new entry. Derivations work in placeholder symbols (coordinate slots, frame values); those
made with ``placeholder(tag)`` are plain symbols whose names no model symbol can have (they
start with a NUL), so they are the same in every process. A Dummy is equal only within its
process: a derivation whose inputs or result hold one is not stored (it is derived each
time).

Entries are pickles in ``<cache>/derivations/<sources digest>/`` (core/files.py's cache
directory, its stale versions pruned alike); one that cannot be read is derived again and
rewritten, and a cache that cannot be written only costs the derivation.
``MBSYNTH_DERIVATION_CACHE=off`` turns the disk off (the benchmark's cold figures).
"""

import hashlib
import importlib
import inspect
import linecache
import marshal
import os
import pickle
import types
from importlib.util import MAGIC_NUMBER
from pathlib import Path

import numpy as np
import sympy as sp
from sympy.core.parameters import evaluate

from ..core.files import cache_dir, mark_and_prune, sources_hash, write_atomically
from ..core.memo import MEMO



def placeholder(tag):
    """The placeholder symbol of ``tag``, the same in every process."""
    return sp.Symbol("\0" + tag)


class Unstable(Exception):
    """A value that cannot be stored: an expression holding a Dummy."""


def _stable(value):
    """``value``, checked to hold no Dummy (nested tuples and lists of expressions and
    matrices)."""
    if isinstance(value, (tuple, list)):
        for v in value:
            _stable(v)
    elif isinstance(value, (sp.Basic, sp.MatrixBase)) and value.has(sp.Dummy):
        raise Unstable(value)
    return value


def remembered(kind, inputs, derive, *, store=_stable, load=lambda stored: stored):
    """``derive()``, from disk when derived before from equal ``inputs`` (see the module
    docstring). ``store``/``load`` turn the result into what is pickled and back (by
    default: sympy expressions, as they are)."""
    folder = _cache_folder()
    if folder is None:
        return derive()
    try:
        key = fingerprint(inputs)
    except Unstable:
        return derive()
    path = folder / f"{kind}-{key}.pkl"
    if path.exists():
        try:
            with evaluate(False):  # stored in canonical form: rebuilt as is, not evaluated again
                stored = pickle.loads(path.read_bytes())
            return load(stored)
        except Exception:  # noqa: BLE001 - a damaged or foreign entry: derive it again
            pass
    result = derive()
    try:
        data = pickle.dumps(store(result), protocol=pickle.HIGHEST_PROTOCOL)
        write_atomically(path, lambda temporary: temporary.write_bytes(data))  # a sweep's processes write alike
    except (Unstable, OSError, pickle.PicklingError, TypeError, AttributeError):
        pass
    return result


def remembered_function(kind, inputs, derive):
    """``remembered`` for a function sympy's lambdify makes (``derive()``): kept as its code
    (marshalled) and where its global names come from (modules' attributes, numbers), so that
    reading it back needs neither a compile nor lambdify's namespace (``from numpy import *``).
    A function reading any other global is derived each time (Unstable)."""
    return remembered(kind, inputs, derive, store=_function_source, load=_function_from_source)


def _function_source(raw):
    """(source, its compiled code marshalled, [(name, module, attribute)] for each global
    name it reads: the attribute of that module ("" the module itself), or with module
    None the value itself) of a lambdified function."""
    source = inspect.getsource(raw)
    code = compile(source, _source_file(source), "exec")
    names = [(name, *_origin(name, raw.__globals__[name])) for name in sorted(_global_names(code))
             if name in raw.__globals__]
    return source, marshal.dumps(code), names


def _function_from_source(stored):
    source, code, names = stored
    namespace = {name: value if module is None else _attribute(module, value) for name, module, value in names}
    code = marshal.loads(code)
    linecache.cache[code.co_filename] = (len(source), None, source.splitlines(True), code.co_filename)  # tracebacks
    exec(code, namespace)  # noqa: S102 - code sympy generated, from our cache
    return namespace["_lambdifygenerated"]


def _attribute(module, attribute):
    """``module``'s ``attribute``, or the module itself for ""."""
    module = importlib.import_module(module)
    return getattr(module, attribute) if attribute else module


def _source_file(source):
    """The file name a generated source's tracebacks show (linecache holds its lines)."""
    return f"<lambdified-{hashlib.sha1(source.encode()).hexdigest()[:12]}>"


def _global_names(code):
    """The names ``code`` and the code nested in it look up (globals among them)."""
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _global_names(const)
    return names


def _origin(name, value):
    """(module, attribute) that ``value``, a lambdified function's global ``name``, is read
    back from, or (None, value) for a number; Unstable for anything else."""
    if isinstance(value, types.ModuleType):
        return value.__name__, ""
    if isinstance(value, (int, float, complex, np.number)):
        return None, value
    module = getattr(value, "__module__", None)
    for attribute in (getattr(value, "__name__", None), name):
        if module and attribute and getattr(importlib.import_module(module), attribute, None) is value:
            return module, attribute
    raise Unstable(name)


def fingerprint(value, seen=None):
    """A digest of ``value`` (nested tuples of sympy expressions and matrices, strings,
    numbers) that is the same in every process (Unstable for a Dummy): each expression node
    hashed once, from its class, an atom's exact content and its arguments' digests
    (``seen``: node -> digest)."""
    seen = {} if seen is None else seen
    if isinstance(value, sp.MatrixBase):
        return fingerprint(("Matrix", value.shape, tuple(value)), seen)
    if isinstance(value, (tuple, list)):
        parts = [fingerprint(v, seen) for v in value]
        return hashlib.sha1(f"{type(value).__name__}({','.join(parts)})".encode()).hexdigest()
    if not isinstance(value, sp.Basic):
        return hashlib.sha1(f"{type(value).__name__}:{value!r}".encode()).hexdigest()
    node = (type(value), value)  # Float(1) and Integer(1) apart, whatever == says
    digest = seen.get(node)
    if digest is None:
        if value.args:
            content = ",".join(fingerprint(arg, seen) for arg in value.args)
        elif isinstance(value, sp.Dummy):
            raise Unstable(value)
        elif isinstance(value, sp.Symbol):
            content = f"{value.name}:{sorted(value.assumptions0.items())}"
        elif isinstance(value, sp.Float):
            content = repr(value._mpf_)
        else:
            content = repr(value)  # integers, rationals, constants (pi, nan, oo)
        digest = seen[node] = hashlib.sha1(f"{type(value).__name__}({content})".encode()).hexdigest()
    return digest


@MEMO.function(1)
def _cache_folder():
    """``<cache>/derivations/<digest of this package's sources and sympy's version>``,
    created (once per process); None when off or not writable."""
    if os.environ.get("MBSYNTH_DERIVATION_CACHE", "").lower() in ("off", "0", "no"):
        return None
    try:
        salt = sp.__version__ + MAGIC_NUMBER.hex()
        digest = sources_hash(Path(__file__).resolve().parents[1], "**/*.py", salt=salt)
        folder = cache_dir() / "derivations" / digest
        folder.mkdir(parents=True, exist_ok=True)
        mark_and_prune(folder)  # and the entries of older sources removed
    except OSError:
        return None
    return folder
