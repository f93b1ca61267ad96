"""Content keys: what makes two model objects equal, whatever process or load made them.

A model (``System``) is a value: two loaded separately from the same file are equal and
hash alike. Its parts, constraints and force elements compare by what defines them (their
sympy expressions, numbers and names), never by identity; ``freeze`` turns such content
into something hashable with that equality.
"""

import dataclasses
import types
from collections.abc import Mapping

import numpy as np
import sympy as sp

_PLAIN = (type(None), bool, int, float, complex, str, bytes, sp.Basic)


def freeze(x):
    """A hashable stand-in for ``x`` that is equal exactly when the contents are: sympy
    matrices as immutable ones, arrays as (dtype, shape, bytes) (sparse ones by their CSR), mappings, sequences and
    sets element by element, dataclasses by their compared fields, objects with a
    ``content()`` method by it. TypeError for anything else (no silent identity)."""
    if isinstance(x, _PLAIN) or isinstance(x, Keyed):
        return x
    if isinstance(x, slice):  # unhashable before Python 3.12
        return ("slice", x.start, x.stop, x.step)
    if isinstance(x, sp.MatrixBase):
        return sp.ImmutableSparseMatrix(x) if isinstance(x, sp.SparseMatrix) else sp.ImmutableDenseMatrix(x)
    if isinstance(x, np.ndarray):
        return ("array", x.dtype.str, x.shape, np.ascontiguousarray(x).tobytes())
    if hasattr(x, "tocsr") and hasattr(x, "nnz"):  # a scipy.sparse array
        csr = x.tocsr()
        return ("sparse", csr.shape, freeze(csr.data), freeze(csr.indices), freeze(csr.indptr))
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, Mapping):
        return ("mapping", tuple((freeze(k), freeze(v)) for k, v in x.items()))
    if isinstance(x, (tuple, list)):
        return tuple(freeze(v) for v in x)
    if isinstance(x, (set, frozenset)):
        return frozenset(freeze(v) for v in x)
    if hasattr(x, "content"):
        return (type(x).__name__, x.content())
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return (type(x).__name__,) + tuple(freeze(getattr(x, f.name)) for f in dataclasses.fields(x) if f.compare)
    raise TypeError(f"no content key for a {type(x).__name__}: give it a content() method")


class Keyed:
    """A model object equal to another of its type with the same ``content()`` (a tuple
    that ``freeze`` made hashable): parts, constraints and force elements."""

    def content(self):
        raise NotImplementedError

    def _key(self):
        key = self.__dict__.get("_content_key")
        if key is None:  # made on first comparison: the object is complete by then
            key = self.__dict__["_content_key"] = (type(self).__name__, freeze(self.content()))
        return key

    def __eq__(self, other):
        return self is other or (type(other) is type(self) and shared_if_equal(self._key(), other, other._key(),
                                                                               "_content_key"))

    def __hash__(self):
        found = self.__dict__.get("_content_hash")
        if found is None:
            found = self.__dict__["_content_hash"] = hash(self._key())
        return found


def shared_if_equal(key, other, other_key, name):
    """Whether the content keys ``key`` and ``other_key`` (``other``'s, kept in its __dict__
    under ``name``) are equal; where they are, ``other`` keeps ``key`` instead, so that the
    next comparison of the two (a cache's lookup on every call) is by identity, at once."""
    if key is other_key:
        return True
    if key != other_key:
        return False
    other.__dict__[name] = key
    return True


def read_only(array):
    """A read-only float copy of ``array`` (a model's initial state: part of its value)."""
    out = np.array(array, dtype=float)
    out.flags.writeable = False
    return out


def frozen(array):
    """Whether ``array`` is a read-only array owning its numbers (a Data's parameter values):
    its content cannot change while it lives, so its identity stands for its content."""
    return isinstance(array, np.ndarray) and not array.flags.writeable and array.flags.owndata


def frozen_mapping(mapping):
    """``mapping`` as a read-only mapping (None stays None)."""
    return None if mapping is None else types.MappingProxyType(dict(mapping))
