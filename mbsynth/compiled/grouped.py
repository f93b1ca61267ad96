"""Many compiled functions evaluated together: one call per shared structure.

Constraints and parts built from one template (``Constraint._place``, a robot's links)
share the raw numpy function of ``symbolic.compile_function`` and differ only in the
coordinates they read and in their numbers. ``Batch`` stacks those arguments (one column
per instance) and evaluates every instance of every shared structure in one compiled call
(the tape, compiled/tape.py), or calls each shared function once, numpy broadcasting every
operation, instead of once per instance in a Python loop. Functions that are not
``Compiled``, or whose raw function does not broadcast, are called one by one.
"""

import operator

import numpy as np

from . import structures
from ..core.values import frozen
from ..symbolic.derive import PARAMETERS, Compiled
from ..core.tolerances import STACKED_CHECK_RTOL

STACK_MIN = 8  # fewer instances than this are called one by one (numpy's per-call cost on small arrays)


class Batch:
    """``functions[i](t, q[indices[i]], qd[indices[i]], p)`` for all i at once; each
    returns a tuple of arrays (one per *slot*: a, b, C, φ, ψ of a constraint; M, Q or T, V
    of a part). A call returns, per slot, the raveled outputs of all functions
    concatenated in order (``slots`` of them). The layout is fixed at the first call.
    ``compiled``: the groups of shared structures are evaluated compiled
    (compiled/structures.py, built at the first call): those on the tape all in one
    ``tape.Program`` call, any other by its own kernel; else by numpy throughout. Which way
    a group goes depends on its structure alone, never on the values of a state."""

    def __init__(self, functions, indices, slots, compiled):
        self.functions, self.slots = list(functions), slots
        self.indices = [np.asarray(i, dtype=int) for i in indices]
        self.layout = None
        self.compiled = compiled

    def __call__(self, t, q, qd, p):
        t = np.float64(t)
        if self.layout is None:
            return self._first(t, q, qd, p)
        total, on_tape, groups, singles, slots = self.layout
        out = np.empty(total)
        if on_tape is not None:
            on_tape(t, q, qd, p, out)
        if groups:
            with np.errstate(all="ignore"):  # NaN and inf are reported by the checks of M, Q, A, b
                for group in groups:
                    out[group.dest] = group(t, q, qd, p)
        for f, idx, dest in singles:
            out[dest] = np.concatenate([np.ravel(x) for x in f(t, q[idx], qd[idx], p)])
        return [out[a:b] for a, b in slots]

    def groups(self):
        """(the groups of shared structures, the functions called one by one), once laid out."""
        _, on_tape, groups, singles, _ = self.layout
        return (on_tape.groups if on_tape is not None else []) + groups, singles

    def _first(self, t, q, qd, p):
        """Call each function alone, lay the outputs out, group the functions that share a
        raw function: those whose structure compiles are evaluated compiled from now on,
        the others stacked on numpy where that reproduces the single calls."""
        outputs = [[np.ravel(x) for x in f(t, q[idx], qd[idx], p)] for f, idx in zip(self.functions, self.indices)]
        count = self.slots
        sizes = np.array([[x.size for x in o] for o in outputs], dtype=int).reshape(len(outputs), count)
        slot_size = sizes.sum(axis=0)
        slot_start = np.concatenate([[0], np.cumsum(slot_size)])
        # position of each function's outputs in the flat result: slot start + the sizes before it
        before = np.cumsum(sizes, axis=0) - sizes
        dests = [np.concatenate([slot_start[j] + before[i, j] + np.arange(sizes[i, j]) for j in range(count)])
                 .astype(int) for i in range(len(outputs))]
        expected = np.concatenate([np.zeros(0)] + [o[j] for j in range(count) for o in outputs])  # slot by slot
        taped, groups, singles = [], [], []
        for members in _shared(self.functions, self.indices):
            group = None
            if isinstance(self.functions[members[0]], Compiled):
                group = _Group([self.functions[i] for i in members], np.array([self.indices[i] for i in members]),
                               np.array([dests[i] for i in members]).T)
                found = structures.kernel(group.raw) if self.compiled else None
                if found is not None and not callable(found):  # a tape.Taped
                    taped.append((group, found))
                    continue
                group.kernel = found
                if found is not None and group.attempt(t, q, qd, p) is None:
                    group.kernel = None  # it raises: numpy serves
                if group.kernel is None and not group.reproduces(t, q, qd, p, expected):
                    group = None
            if group is None:
                singles.extend((self.functions[i], self.indices[i], dests[i]) for i in members)
            else:
                groups.append(group)
        on_tape = _OnTape(taped, t, q, qd, p) if taped else None
        self.layout = (int(slot_start[-1]), on_tape, groups, singles, list(zip(slot_start[:-1], slot_start[1:])))
        return [expected[a:b] for a, b in self.layout[4]]


def _shared(functions, indices):
    """The functions as lists of positions, those that can share one call together."""
    found = {}
    for i, (f, idx) in enumerate(zip(functions, indices)):
        key = (id(f.raw), idx.size, _values_key(f.values), len(f.fixed)) if isinstance(f, Compiled) else ("alone", i)
        found.setdefault(key, []).append(i)
    return list(found.values())


def _values_key(values):
    if not hasattr(values, "picks"):
        return id(values)
    return ("gathered", len(values.fixed), tuple((k, a, i is None) for k, a, i in values.picks))


class _OnTape:
    """The groups whose structures are on the tape (``taped``: (group, its tape.Taped)),
    evaluated by one ``tape.Program`` call. Their stacked constants are kept for the next
    call when they read the parameters alone and the parameters are ``frozen`` (a Data's)."""

    def __init__(self, taped, t, q, qd, p):
        from . import tape  # numba: loaded with the first structure compiled, not with the package

        self.groups = [group for group, _ in taped]
        rows = [len(group.stacked_values(t, q, qd, p)) for group in self.groups]
        self.program = tape.Program([(found, group.columns, count, group.fixed, group.dest)
                                     for (group, found), count in zip(taped, rows)])
        self.constant = all(group.reads <= {PARAMETERS} for group in self.groups)
        self.kept = (None, None)  # (the frozen parameter array, the values read with it)

    def __call__(self, t, q, qd, p, out):
        self.program.call(t, q, qd, p, self._values(t, q, qd, p), out)  # the Program's call, no frame of its own

    def _values(self, t, q, qd, p):
        kept, values = self.kept
        if self.constant and p is kept:
            return values
        values = np.empty(self.program.values_size)
        for group, where in zip(self.groups, self.program.value_slices):
            values[where] = group.stacked_values(t, q, qd, p).ravel()
        if self.constant and frozen(p):
            self.kept = (p, values)
        return values


class _Group:
    """Functions sharing one raw function: evaluated by its own compiled ``kernel`` where
    Batch gives one (compiled/structures.py), else by one stacked numpy call when there are
    at least STACK_MIN of them, else one by one. ``dest`` (outputs × members): where each
    output of each member goes in the flat result. ``reads``: the arguments (positions in
    t, q, q̇, p) the members' constants read."""

    def __init__(self, functions, indices, dest):
        first = functions[0]
        self.raw, self.dest = first.raw, dest
        self.columns = np.ascontiguousarray(indices.T)  # coordinates × members: lambdify unpacks the rows
        self.fixed = np.ascontiguousarray(np.array([f.fixed for f in functions], dtype=float).T)
        # constants that are numbers and arguments (symbolic.gather): stacked, and per argument a
        # the rows of the constants read from it and, per row and member, where in it (None: the
        # argument is a scalar, t), put in by one indexing per argument: those read from the
        # parameters once per read-only parameter array (_with_parameters), the others per call
        self.picks = None
        self.values = first.values
        self.reads = getattr(first.values, "reads", None)  # lambdified (derive._values); gathered: below
        if hasattr(first.values, "picks"):
            self.values = np.ascontiguousarray(np.array([f.values.fixed for f in functions], dtype=float).T)
            picks = _picks(first.values.picks, [f.values.picks for f in functions], self.columns)
            self.picks = [pick for pick in picks if pick[0] != PARAMETERS]
            self.parameter_picks = [pick for pick in picks if pick[0] == PARAMETERS]
            self.gathered_at = (None, self.values)  # (the read-only parameter array, the values with it put in)
            self.reads = {a for a, _, _ in picks}
        self.pick = None  # (itemgetter of the outputs that are arrays, their rows, the others' and theirs)
        self.kernel = None  # the structure's own compiled function, set by Batch

    def __call__(self, t, q, qd, p):
        values = self.stacked_values(t, q, qd, p)
        if self.kernel is not None:
            result = np.empty(self.dest.shape)
            self.kernel(t, q, qd, p, self.columns, values, self.fixed, result)
            return result
        return self._numpy(t, q, qd, p, values)

    def stacked_values(self, t, q, qd, p):
        """The members' constants at (t, q, q̇, p): rows × members."""
        if self.picks is None:
            return _stacked(self.values.listed(t, q[self.columns], qd[self.columns], p), self.dest.shape[1])
        return self._gathered(t, q, qd, p)

    def _gathered(self, t, q, qd, p):
        """The stacked constants with each member's arguments put in."""
        values = self._with_parameters(p)
        if self.picks:
            values, given = values.copy(), (t, q, qd)
            for a, rows, at in self.picks:
                values[rows] = given[a] if at is None else given[a][at]
        return values

    def _with_parameters(self, p):
        """The stacked constants with the parameters ``p`` put in: kept for the next call when
        ``p`` is ``frozen`` (a Data's parameter values)."""
        kept, values = self.gathered_at
        if p is kept or not self.parameter_picks:
            return values
        values = self.values.copy()
        for _, rows, at in self.parameter_picks:
            values[rows] = p[at]
        if frozen(p):
            self.gathered_at = (p, values)
        return values

    def _numpy(self, t, q, qd, p, values):
        members = self.dest.shape[1]
        if members < STACK_MIN:
            result = np.empty(self.dest.shape)
            for m in range(members):
                cols = self.columns[:, m]
                result[:, m] = self.raw(t, q[cols], qd[cols], p, values[:, m], self.fixed[:, m])
            return result
        qs, qds = q[self.columns], qd[self.columns]
        out = self.raw(t, qs, qds, p, values, self.fixed)
        if self.pick is None:
            arrays = [k for k, x in enumerate(out) if np.ndim(x) > 0]
            others = [k for k in range(len(out)) if np.ndim(out[k]) == 0]
            self.pick = (_getter(arrays), arrays, _getter(others), others)
        get_arrays, arrays, get_others, others = self.pick
        result = np.empty(self.dest.shape)
        if arrays:
            result[arrays] = np.array(get_arrays(out), dtype=float)
        if others:
            result[others] = np.array(get_others(out), dtype=float)[:, None]
        return result

    def attempt(self, t, q, qd, p):
        """This group's call, or None where it raises (its own kernel compiled for other
        arguments, a raw function that does not broadcast)."""
        try:
            with np.errstate(all="ignore"):
                return self(t, q, qd, p)
        except Exception:  # noqa: BLE001 - the functions are then called one by one
            return None

    def reproduces(self, t, q, qd, p, expected):
        """Whether this group's call gives the single calls' outputs ``expected`` (its
        places in them)."""
        got = self.attempt(t, q, qd, p)
        return got is not None and stacked_agrees(got, expected[self.dest])


def _picks(first, every, columns):
    """[(argument a, rows of the constants read from it, their places in it: None for a
    scalar argument, else rows × members)] from the picks (k, a, i) of the first member and of
    every member (``every``): a coordinate or velocity slot i is the member's column of
    ``columns``, a position in the parameters is the member's own."""
    members = np.arange(len(every))
    by_argument = {}
    for n, (k, a, i) in enumerate(first):
        at = None if i is None else np.array([picks[n][2] for picks in every])
        if at is not None and a in (1, 2):
            at = columns[at, members]
        by_argument.setdefault(a, []).append((k, at))
    return [(a, np.array([k for k, _ in found]), None if found[0][1] is None else np.array([at for _, at in found]))
            for a, found in by_argument.items()]


def stacked_agrees(got, want):
    """Equal to STACKED_CHECK_RTOL of the largest finite value, NaN where NaN."""
    scale = np.abs(want[np.isfinite(want)]).max(initial=0.0)
    return got.shape == want.shape and np.allclose(got, want, rtol=STACKED_CHECK_RTOL,
                                                   atol=STACKED_CHECK_RTOL * scale,
                                                   equal_nan=True)


def _getter(positions):
    """A function picking ``positions`` of a sequence as a tuple (one C call)."""
    if len(positions) == 1:
        k = positions[0]
        return lambda seq: (seq[k],)
    return operator.itemgetter(*positions) if positions else (lambda seq: ())


def _stacked(values, members):
    """The values as rows of a (len(values), members) array, scalars repeated along their row."""
    stacked = np.empty((len(values), members))
    for row, value in zip(stacked, values):
        row[...] = value
    return stacked
