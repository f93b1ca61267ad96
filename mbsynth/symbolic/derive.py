"""Symbolic derivations done once per model, and their compilation to numpy.

- ``lagrange(T, V, F, q, qd, t)``: the unconstrained equation ``M q̈ = Q`` (2.1)
  of a part given by its kinetic energy T, potential energy V and generalized
  forces F, from Lagrange's equations.
- ``differentiate(phi, q, qd, t)``: a constraint ``phi = 0`` differentiated to
  the row ``A q̈ = b`` (2.4), once if phi contains velocities, twice if not;
  ``differentiate_through`` the same through symbols standing for expressions of q.
- ``generalized_force(V, efforts, q, qd)``: Q of a potential and (effort, rate) pairs.
- ``compile_function(args, exprs)``: one fast numpy function for many expressions.

Both the derivations and the compiled functions are shared between expressions of the
same *structure* (``canonical``): a robot's fifty revolute joints differ only in the
names of their coordinates and the numbers of their frames, so their rows are
differentiated and compiled a handful of times, not fifty.
"""

import numpy as np
import sympy as sp

from .cache import Unstable, fingerprint, placeholder, remembered, remembered_function
from .dag import Replacing, atoms_of, replaced, symbols_in
from ..core.memo import MEMO
from ..core.values import frozen

T_SYMBOL = sp.Symbol("t")
LAMBDIFIED_KEPT = 65536  # structures whose numpy function the one cache keeps (far above a model's count)
PARAMETERS = 3  # the position of the model's parameters among a part's or constraint's arguments (t, q, q̇, p)
_LARGEST = sp.Float(np.finfo(float).max)
# pi and e as numpy floats, so that all arithmetic of a compiled expression is numpy's:
# Python floats raise on overflow and division by zero ((2*pi + 1e308)**251, 1/(1 - t) at
# t = 1) where numpy's give inf, which the checks of M, Q, A, b then report
_FLOAT64 = {"pi": np.float64(np.pi), "e": np.float64(np.e)}
SIMPLIFY_MAX_OPS = 60  # sympy.simplify's cost grows fast beyond this (nested sin, exp)
# an expression of more nodes has more than SIMPLIFY_MAX_OPS operations (a node adds at most about
# three nodes per operation): not counted by count_ops, whose cost grows with the expression
SIMPLIFY_MAX_NODES = 10 * SIMPLIFY_MAX_OPS


def lagrange(T, V, F, q, qd, t=T_SYMBOL):
    """M and Q of (2.1) from Lagrange's equations d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q = F.

    Expanding d/dt ∂T/∂q̇ = (∂²T/∂q̇²) q̈ + (∂²T/∂q̇∂q) q̇ + ∂²T/∂q̇∂t gives
    M = ∂²T/∂q̇², Q = F + ∂T/∂q − ∂V/∂q − (∂²T/∂q̇∂q) q̇ − ∂²T/∂q̇∂t.
    Each entry is simplified when it is small (``tidy``). Derived once per structure
    (``energy_template``)."""
    found = energy_template(T, V, F, q, qd, t)
    if found is None:  # symbols no slot can stand for
        return tuple(map(sp.Matrix, _lagrange(sp.sympify(T), sp.sympify(V), tuple(sp.sympify(f) for f in F),
                                              tuple(q), tuple(qd), t)))
    (q_slots, qd_slots), constants, (M, Q, _, _, _) = found
    back = dict(zip(q_slots, q))
    back.update(zip(qd_slots, qd))
    back.update(constants)
    return sp.Matrix(M.xreplace(back)), sp.Matrix(Q.xreplace(back))


def energy_template(T, V, F, q, qd, t=T_SYMBOL):
    """((q slots, q̇ slots), constants, (M, Q, T, V, F)): ``lagrange``'s M and Q, and T, V
    and the forces F, written in placeholder slots for the coordinates q, the velocities
    q̇ and the other symbols (parameters; ``constants``: (slot, symbol) pairs, by name).
    Copies of a part that differ only in the names of their symbols (a cell used a
    thousand times, each copy with parameters of its own) get the same template, derived
    and compiled once. None where a symbol is no plain Symbol (``_plain``)."""
    T, V, F = sp.sympify(T), sp.sympify(V), tuple(sp.sympify(f) for f in F)
    q, qd = tuple(q), tuple(qd)
    others = sorted(symbols_in((T, V, *F)) - set(q) - set(qd) - {t}, key=str)
    symbols = q + qd + tuple(others)
    if len(set(symbols)) < len(symbols) or not all(_plain(s) for s in symbols):
        return None
    slots = tuple(_ENERGY[i] for i in range(len(symbols)))
    forward = dict(zip(symbols, slots))
    T, V, F = T.xreplace(forward), V.xreplace(forward), tuple(f.xreplace(forward) for f in F)
    q_slots, qd_slots = slots[:len(q)], slots[len(q):2 * len(q)]
    M, Q = _lagrange(T, V, F, q_slots, qd_slots, t)
    return (q_slots, qd_slots), tuple(zip(slots[2 * len(q):], others)), (M, Q, T, V, F)


def _plain(symbol):
    """Whether a slot (a symbol without assumptions, equal in every process) can stand for
    ``symbol`` in a derivation: a plain Symbol (a Dummy or an assumption such as positive
    would change what sympy simplifies)."""
    return type(symbol) is sp.Symbol and symbol.assumptions0 == _PLAIN


@MEMO.function(1024)
def _lagrange(T, V, F, q, qd, t):
    """``lagrange`` of these T, V, F in these q, q̇: once per process, and kept on disk (cache.py)."""
    def derive():
        qs, qds = sp.Matrix(q), sp.Matrix(qd)
        p = sp.Matrix([T]).jacobian(qds).T  # generalized momenta ∂T/∂q̇
        M = p.jacobian(qds)
        Q = (sp.Matrix(F) + sp.Matrix([T - V]).jacobian(qs).T
             - p.jacobian(qs) * qds - p.diff(t))
        return M.applyfunc(tidy), Q.applyfunc(tidy)

    M, Q = remembered("lagrange", (T, V, F, q, qd, t), derive)
    return sp.ImmutableMatrix(M), sp.ImmutableMatrix(Q)


def tidy(expr, max_ops=SIMPLIFY_MAX_OPS):
    """sympy.simplify for expressions small enough to be worth it (it is slow on big ones)."""
    small = not exceeds(expr, SIMPLIFY_MAX_NODES) and sp.count_ops(expr) <= max_ops
    return sp.simplify(expr) if small else expr


def exceeds(expr, limit):
    """Whether ``expr`` (or a matrix's entries that are not numbers) has more than ``limit``
    nodes, counted only up to there: a size test in time bounded by ``limit``."""
    entries = expr if isinstance(expr, sp.MatrixBase) else [sp.sympify(expr)]
    count = 0
    for entry in entries:
        if entry.is_Number:
            continue
        for _ in sp.preorder_traversal(entry):
            count += 1
            if count > limit:
                return True
    return False


def jacobian(exprs, symbols):
    """∂exprs/∂symbols (a len(exprs) × len(symbols) matrix), differentiating each
    expression only by the symbols it contains: a model has hundreds of coordinates and
    a joint's rows involve fourteen."""
    exprs, symbols = [sp.sympify(e) for e in exprs], list(symbols)
    out = sp.zeros(len(exprs), len(symbols))
    for i, e in enumerate(exprs):
        free = symbols_in([e])
        for j, s in enumerate(symbols):
            if s in free:
                out[i, j] = e.diff(s)
    return out


class JointValue(sp.Dummy):
    """A joint's angle (``hinge.angle``) in a constraint: a symbol standing for ``value``,
    an expression of the coordinates (an atan2 of the parts' axes), whose time derivative
    is ``rate`` (the joint's rate, linear in q̇). Constraints on it are differentiated by
    the chain rule through the rate — cheap — instead of through the atan2 twice, which
    is exact on the constraint manifold, where d(value)/dt = rate (joint_values.py); the
    value is put in afterwards (``expand_joint_values``)."""

    def __new__(cls, name, value, rate):
        symbol = super().__new__(cls, name)
        symbol.value, symbol.rate = sp.sympify(value), sp.sympify(rate)
        return symbol


def joint_values_in(expr):
    """The JointValue symbols of ``expr``."""
    return [s for s in symbols_in([expr]) if isinstance(s, JointValue)]


def expand_joint_values(expr):
    """``expr`` with its JointValue symbols replaced by their values."""
    found = joint_values_in(expr)
    return replaced([sp.sympify(expr)], {s: s.value for s in found})[0] if found else expr


def turn_residual(phi):
    """A position-level row φ with its JointValue angles replaced by their values, taken
    modulo the turn where φ is affine in them with coefficients ±c (c a number): φ − P ⌊φ/P + ½⌋,
    P = 2π|c|. A joint's angle is read in (−π, π], so a plain servo row ``angle − θ(t)``
    would jump by P at each reading's wrap while θ(t) runs on; a rotation that meets θ(t)
    meets it modulo a turn, and the row's residual is the nearest one (A and b, through
    the rate, are the row's own). Other rows are as ``expand_joint_values`` gives them."""
    angles = joint_values_in(phi)
    if not angles:
        return phi
    phi = sp.sympify(phi)
    sizes = {abs(sp.diff(phi, s)) for s in angles}
    if len(sizes) != 1 or not all(c.is_number and c != 0 for c in sizes):
        return expand_joint_values(phi)
    period = 2 * sp.pi * sizes.pop()
    value = expand_joint_values(phi)
    return value - period * sp.floor(value / period + sp.Rational(1, 2))


def time_derivative(expr, q, qd, t=T_SYMBOL):
    """d/dt of an expression of (q, t) along the motion: (∂e/∂q) q̇ + ∂e/∂t, and the
    chain rule Σ (∂e/∂s) ṡ through the JointValue symbols s it holds."""
    chain = sum((sp.diff(expr, s) * s.rate for s in joint_values_in(expr)), sp.S.Zero)
    return (jacobian([expr], q) * sp.Matrix(qd))[0] + sp.diff(expr, t) + chain


def generalized_force(V, efforts, q, qd):
    """Q = −∂V/∂q + Σ effort ∂rate/∂q̇ (virtual power; each rate linear in q̇), a column over
    q; kept on disk (cache.py)."""
    efforts = tuple((sp.sympify(effort), sp.sympify(rate)) for effort, rate in efforts)

    def derive():
        Q = -jacobian([V], q).T
        for effort, rate in efforts:
            Q += effort * jacobian([rate], qd).T
        return Q

    return remembered("generalized-force", (sp.sympify(V), efforts, tuple(q), tuple(qd)), derive)


class Slots:
    """Positional placeholder symbols ``<prefix><i>``, named so that they clash with no
    model's names and stay the same across processes (cache.placeholder)."""

    def __init__(self, prefix):
        self.prefix, self.items = prefix, []

    def __getitem__(self, i):
        while len(self.items) <= i:
            self.items.append(placeholder(f"{self.prefix}{len(self.items)}"))
        return self.items[i]


_ARGUMENT, _RATE, _NUMBER = Slots("a"), Slots("r"), Slots("k")
_ENERGY = Slots("e")  # the symbols of a part's energies (``lagrange``)
_PLAIN = sp.Symbol("x").assumptions0
_PICKED = Slots("p")  # the parameters a compiled function reads from its whole parameter argument


def _numbers(expr, found, seen=None):
    """The non-integer numbers of ``expr`` into the dict ``found``, in preorder, numeric
    exponents left alone (x**2, sqrt); ``seen``: the subexpressions walked already (each
    walked once, in the order of its first occurrence)."""
    seen = set() if seen is None else seen
    if id(expr) in seen:
        return
    seen.add(id(expr))
    if expr.is_Number:
        if expr.is_Float or (expr.is_Rational and not expr.is_Integer):  # not nan, oo
            found.setdefault(expr, None)
        return
    args = expr.args[:1] if expr.is_Pow and expr.exp.is_Number else expr.args
    for arg in args:
        _numbers(arg, found, seen)


def canonical(exprs, symbols):
    """(placeholder forms of ``exprs``, the numbers they stand for): ``symbols`` become
    positional placeholders and each distinct non-integer number a placeholder ``k_i``.
    Two expressions with equal placeholder forms have the same structure, whatever the
    names of their symbols and the values of their numbers."""
    found, seen = {}, set()
    for e in exprs:
        _numbers(e, found, seen)
    forward = {s: _ARGUMENT[i] for i, s in enumerate(symbols)}
    forward.update({x: _NUMBER[i] for i, x in enumerate(found)})
    return tuple(replaced(exprs, forward)), tuple(found)


def differentiated(exprs, q, qd, t=T_SYMBOL):
    """(A rows (sparse, len(exprs) × len(q)), b, velocity-level forms) of the
    constraints ``exprs`` = 0 (``differentiate`` each), derived once per structure: the
    coordinates, velocities and parameters involved become placeholder slots (``canonical``)."""
    exprs = [sp.sympify(e) for e in exprs]
    if any(joint_values_in(e) for e in exprs):  # the chain rule through joint rates (JointValue)
        rows = [differentiate(e, q, qd, t) for e in exprs]
        entries = {(r, j): expand_joint_values(x) for r, row in enumerate(rows) for j, x in enumerate(row[0]) if x != 0}
        return (sp.SparseMatrix(len(exprs), len(q), entries), [expand_joint_values(row[1]) for row in rows],
                [expand_joint_values(row[2]) for row in rows])
    (a, b, psi), _, slots, involved, constants = differentiated_template(exprs, q, qd, t)
    back = dict(constants)
    back.update(zip(slots[0], (q[i] for i in involved)))
    back.update(zip(slots[1], (qd[i] for i in involved)))
    entries, put = {}, Replacing(back)
    for r, row in enumerate(a):
        for j, entry in enumerate(row):
            if entry != 0:
                entries[r, involved[j]] = put(entry)
    return sp.SparseMatrix(len(exprs), len(q), entries), [put(x) for x in b], [put(x) for x in psi]


def differentiated_template(exprs, q, qd, t=T_SYMBOL):
    """((a rows over the involved coordinates, b, ψ), φ, (q slots, q̇ slots), the involved
    coordinates (indices), constants) of the constraints ``exprs`` = 0 (none may hold a
    JointValue), all in placeholder slots (``canonical``): the coordinates and velocities
    involved, the parameters (constants: (slot, symbol)) and the numbers (constants:
    (slot, number)). Constraints alike but for their symbols and numbers share it."""
    where = positions(q, qd)
    free = symbols_in(exprs)
    involved = sorted({where[s] for s in free if s in where})
    others = sorted((s for s in free if s not in where and s != t and _plain(s)), key=str)  # parameters
    count = len(involved)
    forms, numbers = canonical(exprs, [q[i] for i in involved] + [qd[i] for i in involved] + others)
    constants = tuple(zip((_ARGUMENT[2 * count + j] for j in range(len(others))), others))
    constants += tuple((_NUMBER[j], x) for j, x in enumerate(numbers))
    slots = tuple(_ARGUMENT[j] for j in range(count)), tuple(_ARGUMENT[count + j] for j in range(count))
    return _differentiated(forms, count, t), forms, slots, involved, constants


def placed_values(slots, coordinates, constants, q, qd):
    """{placeholder: what it stands for}: the constants, and the model's coordinate and
    velocity symbols at ``coordinates`` for the slots (q slots, q̇ slots)."""
    put = dict(constants)
    put.update({s: q[c] for s, c in zip(slots[0], coordinates)})
    put.update({s: qd[c] for s, c in zip(slots[1], coordinates)})
    return put


_POSITIONS = MEMO.table("coordinate positions", 1)  # the last pair asked: every constraint of a model asks for it


def positions(q, qd):
    """{symbol: index} of the coordinates q and velocities q̇, kept for the last pair asked."""
    key = (tuple(q), tuple(qd))
    last = _POSITIONS.last()
    if last is not None and last[0] == key:  # tuples of the same symbols compare by identity first: fast
        return last[1]

    def make():
        where = {s: i for i, s in enumerate(key[0])}
        where.update({s: i for i, s in enumerate(key[1])})
        return where
    return _POSITIONS.get(key, make)


@MEMO.function(4096)
def _differentiated(forms, count, t):
    """``differentiate`` of each placeholder form in the coordinates a_0 … a_{count−1}
    and velocities a_count …: (rows of a over the involved coordinates, b, ψ)."""
    def derive():
        q = [_ARGUMENT[i] for i in range(count)]
        qd = [_ARGUMENT[count + i] for i in range(count)]
        rows = [differentiate(e, q, qd, t) for e in forms]
        return tuple(tuple(r[0]) for r in rows), tuple(r[1] for r in rows), tuple(r[2] for r in rows)

    return remembered("differentiated", (forms, count, t), derive)


def differentiate(phi, q, qd, t=T_SYMBOL):
    """Row (a, b, phidot) of A q̈ = b (2.4) for the constraint phi(q, q̇, t) = 0.

    A position-level phi(q, t) is differentiated twice (phidot = d phi/dt); a
    velocity-level phi(q, q̇, t) once (phidot is phi itself). With ψ the
    velocity-level form, ψ̇ = (∂ψ/∂q̇) q̈ + (∂ψ/∂q) q̇ + ∂ψ/∂t = 0, so
    a = ∂ψ/∂q̇ and b = −(∂ψ/∂q) q̇ − ∂ψ/∂t (plus the chain rule through JointValue
    symbols, whose rates are exact on the manifold).
    """
    velocity_level = bool(set(qd) & symbols_in([phi]))
    psi = phi if velocity_level else time_derivative(phi, q, qd, t)
    a = jacobian([psi], qd)
    chain = sum((sp.diff(psi, s) * s.rate for s in joint_values_in(psi)), sp.S.Zero)  # JointValue symbols
    b = -(jacobian([psi], q) * sp.Matrix(qd))[0] - sp.diff(psi, t) - chain
    return a, b, psi


def differentiate_through(phi, values, q, qd, t=T_SYMBOL):
    """``differentiate`` of a position-level φ(x) written in symbols x that stand for
    ``values`` ({x_k: x_k(q, t)}), by the chain rule: φ differentiated in the few x, each
    value in q, never φ(x(q)) twice through q (a closed-form distance between two bodies'
    points and axes). With ẍ_k = a_k q̈ − b_k (each value's own row): ψ = Σ ∂φ/∂x_k ẋ_k,
    a = Σ ∂φ/∂x_k a_k, b = Σ ∂φ/∂x_k b_k − Σ ∂²φ/∂x_j∂x_k ẋ_j ẋ_k. (a as a sparse row, b, ψ)
    in q, q̇, t. A Piecewise φ is differentiated branch by branch: each ∂φ/∂x_k and the sum
    of second derivatives is one Piecewise of its conditions."""
    x = tuple(values)
    rows = [differentiate(sp.sympify(values[s]), q, qd, t) for s in x]
    put = dict(values)
    put.update({_RATE[k]: row[2] for k, row in enumerate(rows)})
    conditions, branches = _chain_forms(sp.piecewise_fold(sp.sympify(phi)), x)
    put = Replacing(put)  # one walk of the subexpressions the branches share
    conditions = None if conditions is None else [put(c) for c in conditions]

    def pick(parts):
        parts = [put(part) for part in parts]
        return parts[0] if conditions is None else sp.Piecewise(*zip(parts, conditions), evaluate=False)
    gradient = [pick([g[k] for g, _ in branches]) for k in range(len(x))]
    entries = {}
    for g, row in zip(gradient, rows):
        for (_, j), entry in sp.SparseMatrix(row[0]).todok().items():
            entries[0, j] = entries.get((0, j), sp.S.Zero) + g * entry
    b = sum((g * row[1] for g, row in zip(gradient, rows)), sp.S.Zero) - pick([quadratic for _, quadratic in branches])
    psi = sum((g * row[2] for g, row in zip(gradient, rows)), sp.S.Zero)
    return sp.SparseMatrix(1, len(q), entries), b, psi


@MEMO.function(256)
def _chain_forms(phi, x):
    """(the conditions of φ's branches, or None for one smooth φ; per branch (∂φ/∂x_k, and
    Σ_jk ∂²φ/∂x_j∂x_k r_j r_k in the rate slots r = _RATE)), once per φ in a process."""
    pieces = phi.args if isinstance(phi, sp.Piecewise) else ((phi, sp.true),)
    branches = []
    for expr, _ in pieces:
        gradient = [sp.diff(expr, s) for s in x]
        free = symbols_in([expr])
        quadratic = sp.S.Zero
        for k, g in enumerate(gradient):
            for j in range(k + 1):
                if x[j] in free and g != 0:
                    quadratic += (1 if j == k else 2) * sp.diff(g, x[j]) * _RATE[j] * _RATE[k]
        branches.append((gradient, quadratic))
    return (tuple(c for _, c in pieces) if isinstance(phi, sp.Piecewise) else None), tuple(branches)


def compile_function(args, exprs, constants=(), dtype=float, picked=None):
    """A numpy function of ``args`` returning a tuple of float arrays, one per entry of
    ``exprs`` (scalars, vectors or matrices), with common subexpressions shared.
    ``dtype=complex`` keeps complex arguments complex (complex-step derivatives,
    linearization.py); the constants must then be numbers.

    ``constants``: (placeholder, value) pairs — ``exprs`` may hold the placeholders, whose
    values (numbers or expressions of ``args``) are put in at each evaluation, so that
    expressions shared by many instances (constraints.joints) are compiled once.

    ``picked``: the position in ``args`` of a list of symbols (the model's parameters) that
    the function is given whole and of which ``exprs`` read a few: those few become
    constants picked from it at each evaluation (``_picking``), so that what is compiled is
    the same however long the list and wherever in it they stand — copies of a part, each
    with parameters of its own, share one compiled function, and a model of thousands of
    parameters compiles no function of thousands of arguments."""
    shapes = [e.shape if isinstance(e, sp.MatrixBase) else () for e in exprs]
    flat = [x if isinstance(x, sp.Basic) else sp.sympify(x)
            for e in exprs for x in (e.flat() if isinstance(e, sp.MatrixBase) else [e])]
    if not flat:
        def empty(*_):
            return tuple(np.zeros(s) for s in shapes)
        return empty
    given, picks = args, ()
    if picked is not None:
        args, flat, constants, picks = _picking(args, picked, flat, constants)
    frozen = _frozen(args)
    raw, numbers = _compiled(frozen, tuple(flat), tuple(c[0] for c in constants))
    fixed = np.array([_as_double(x) for x in numbers], dtype=float)
    values = tuple(sp.sympify(c[1]) for c in constants)
    if picked is not None and not all(v.is_Number or v in _positions_in(frozen, picks) for v in values):
        frozen, picks = _frozen(given), ()  # constants of more than numbers and picks: over the whole list
    return Compiled(raw, _values(frozen, values, picks), fixed, shapes, dtype)


_WHOLE = placeholder("whole")  # a compiled function's argument ``picked``, read only through constants


def _picking(args, position, flat, constants):
    """(``args`` with the list at ``position`` replaced by one symbol, ``_WHOLE``; ``flat``
    with the symbols of that list it reads replaced by placeholders; ``constants`` with
    (placeholder, symbol) pairs added for them, in the list's order; and where each symbol
    of the list that a constant stands for is: (symbol, (position, index in the list)))."""
    index = _index_of(args[position])
    used = sorted((s for s in symbols_in(flat) if s in index), key=index.__getitem__)
    forward = {s: _PICKED[i] for i, s in enumerate(used)}
    constants = tuple(constants) + tuple((slot, s) for s, slot in forward.items())
    return (tuple(args[:position]) + (_WHOLE,) + tuple(args[position + 1:]),
            replaced(flat, forward) if forward else flat, constants,
            tuple((v, (position, index[v])) for _, v in constants if v in index))


_INDEX = MEMO.table("symbol positions", 1)  # the last list asked: every part and constraint asks for the parameters


def _index_of(symbols):
    """{symbol: its position in ``symbols``}, kept for the last list asked."""
    symbols = tuple(symbols)
    last = _INDEX.last()
    if last is not None and last[0] == symbols:  # tuples of the same symbols compare by identity first: fast
        return last[1]
    return _INDEX.get(symbols, lambda: {s: i for i, s in enumerate(symbols)})


class Compiled:
    """The function ``compile_function`` returns: ``raw`` (shared by every function of the
    same structure, ``canonical``) applied to the arguments, the values of the constants
    (``values``: a function of the arguments) and this instance's numbers ``fixed``.
    grouped.py calls ``raw`` once for many instances, on stacked arguments."""

    def __init__(self, raw, values, fixed, shapes, dtype=float):
        self.raw, self.values, self.fixed, self.shapes, self.dtype = raw, values, fixed, shapes, dtype
        self.splits = np.cumsum([int(np.prod(s)) for s in shapes])[:-1]

    def __call__(self, *given):
        given = [np.float64(v) if isinstance(v, (int, float)) else v for v in given]
        with np.errstate(all="ignore"):  # NaN and inf are reported by the checks of M, Q, A, b
            out = np.asarray(self.raw(*given, self.values(*given), self.fixed), dtype=self.dtype)
        return tuple(part.reshape(shape) for part, shape in zip(np.split(out, self.splits), self.shapes))


@MEMO.function(4096)
def _compiled(args, flat, placeholders):
    """(numpy function of (args, placeholder values, numbers), the numbers): the
    expressions in ``canonical`` form, compiled once per structure. Both the canonical
    form's digest and numbers and the compiled source are kept on disk
    (cache.py): a model built again in a fresh process skips ``canonical``."""
    symbols = _flat(args) + list(placeholders)
    slots = _placed(args + (placeholders,), iter(_ARGUMENT[i] for i in range(len(symbols))))
    derived = []

    def derive():
        derived.append(canonical(flat, symbols))
        forms, numbers = derived[0]
        try:
            return _structure_digest((slots, len(numbers), forms)), numbers
        except Unstable:  # a Dummy in the forms: a structure of this process alone
            return None, numbers

    digest, numbers = remembered("canonical", (args, flat, placeholders), derive, store=_stable_record)

    def structure():
        """(argument slots, canonical forms): what compiled/structures.py compiles with numba."""
        forms = (derived[0] if derived else canonical(flat, symbols))[0]
        return slots + (tuple(_NUMBER[i] for i in range(len(numbers))),), forms

    return _lambdified(digest, structure), numbers


@MEMO.function(4096)
def _structure_digest(structure):
    """``fingerprint`` of a structure (argument slots, count of numbers, canonical forms):
    once per structure in a process, however many instances have it."""
    return fingerprint(structure)


_LAMBDIFIED = MEMO.table("lambdified structures", LAMBDIFIED_KEPT)  # structure digest -> its numpy function


def _lambdified(digest, structure):
    """The numpy function of the structure ``digest`` (``structure()``: its argument slots
    and forms), made once per structure: joints alike, and models loaded again (a sweep's
    workers, a file checked then simulated) reuse it."""
    def derive():
        args, forms = _positional(*structure())
        return sp.lambdify(args, [beyond_double_as_inf(x) for x in forms], modules=[_FLOAT64, "numpy"], cse=True,
                           use_imps=False)  # no implemented_function here: its search walks the whole tree

    def make():
        raw = derive() if digest is None else remembered_function("lambdified", digest, derive)
        raw.structure = _kernel_view(structure)  # for compiled/structures.py, which compiles it with numba
        raw.digest = digest  # where compiled/structures.py keeps its tape on disk (None: not kept)
        return raw
    return make() if digest is None else _LAMBDIFIED.get(digest, make)


def _kernel_view(structure):
    """``structure`` as compiled/structures.py reads it: (t, then a tuple of slots per
    argument): an argument given whole (``compile_function``'s ``picked``, one slot) is
    read only through constants, no slots of its own."""
    def view():
        args, forms = structure()
        return tuple(() if i and not isinstance(a, tuple) else a for i, a in enumerate(args)), forms
    return view


def _stable_record(record):
    if record[0] is None:
        raise Unstable(record)
    return record


def _positions_in(args, picks=()):
    """{symbol: (argument a, position i or None)} of the symbols of ``args`` (nested one
    deep) and of ``picks`` ((symbol, (a, i)) pairs)."""
    where = {s: (a, None) for a, s in enumerate(args) if isinstance(s, sp.Symbol)}
    where.update({s: (a, i) for a, group in enumerate(args) if isinstance(group, tuple) for i, s in enumerate(group)})
    where.update(picks)
    return where


@MEMO.function(4096)
def _values(args, values, picks=()):
    """A function of ``args`` giving the array of ``values``: gathered from numbers and picks
    (k, argument a, position i or None) of the arguments (``picks``: where symbols read from
    an argument given whole stand) where that is all they are, else lambdified (its
    ``reads``: the positions of the arguments the values read; grouped.py keeps values that
    read the parameters alone; ``listed``: the values as a list)."""
    where = _positions_in(args, picks)
    if all(v.is_Number or v in where for v in values):  # numbers, and arguments (a joint's effort τ)
        fixed = np.array([_as_double(v) if v.is_Number else 0.0 for v in values], dtype=float)
        picks = tuple((k, *where[v]) for k, v in enumerate(values) if not v.is_Number)
        by_argument = _by_argument(picks)

        from_parameters = bool(picks) and all(a == PARAMETERS for a, _, _ in by_argument)
        kept = [(None, None)]  # (a frozen parameter array, the values read from it)

        def gathered(*given):
            if not picks:
                return fixed
            if from_parameters and kept[0][0] is given[PARAMETERS]:
                return kept[0][1]
            read = [(np.asarray(given[a]), rows, at) for a, rows, at in by_argument]
            out = fixed.astype(np.result_type(fixed, *(x for x, _, _ in read)))
            for x, rows, at in read:
                out[rows] = x if at is None else x[at]
            if from_parameters and frozen(given[PARAMETERS]):  # its identity stands for its content
                out.flags.writeable = False
                kept[0] = (given[PARAMETERS], out)
            return out
        gathered.fixed, gathered.picks = fixed, picks  # grouped.py stacks these instead of calling
        return gathered

    def derive():
        named, forms = _positional(args, values)
        return sp.lambdify(named, [beyond_double_as_inf(v) for v in forms], modules=[_FLOAT64, "numpy"], use_imps=False)

    raw = remembered_function("values", (args, values), derive)

    def evaluated(*given):
        return np.asarray(raw(*given), dtype=float)
    evaluated.reads = {where[s][0] for v in values for s in v.free_symbols if s in where}
    evaluated.listed = raw  # each value alone, a number or an array: grouped.py stacks them
    return evaluated


def _by_argument(picks):
    """The picks (k, argument a, position i or None) as one (a, rows k, positions i or None)
    per argument: one indexing per argument puts them in."""
    found = {}
    for k, a, i in picks:
        found.setdefault(a, []).append((k, i))
    return [(a, np.array([k for k, _ in pairs]), None if pairs[0][1] is None else np.array([i for _, i in pairs]))
            for a, pairs in found.items()]


def _positional(args, forms):
    """(``args`` with each symbol renamed by its position — ``_2_5`` for args[2][5] — and
    ``forms`` in those names), for lambdify: its code orders terms by the names, so it reads
    the same in every process (a Dummy's name counts the Dummies the process made before)."""
    names = {}

    def rename(x, path):
        if isinstance(x, (list, tuple)):
            return tuple(rename(y, path + (i,)) for i, y in enumerate(x))
        if isinstance(x, sp.Symbol):
            names[x] = sp.Symbol("_" + "_".join(str(i) for i in path))
            return names[x]
        return x

    named = rename(tuple(args), ())
    return named, replaced([sp.sympify(f) for f in forms], names)


def _frozen(args):
    """``args`` with its lists made tuples (hashable), nested."""
    return tuple(_frozen(a) if isinstance(a, (list, tuple)) else a for a in args)


def _flat(args):
    """The symbols of nested argument lists, in order."""
    return [s for a in args for s in (_flat(a) if isinstance(a, (list, tuple)) else [a])]


def _placed(args, slots):
    """``args`` (nested lists) with each symbol replaced by the next of ``slots``; tuples."""
    return tuple(_placed(a, slots) if isinstance(a, (list, tuple)) else next(slots) for a in args)


def _as_double(x):
    """A number as a double; ±inf beyond the double range (as float arithmetic gives)."""
    return float(x) if abs(x) <= _LARGEST else float(sp.sign(x)) * np.inf


def beyond_double_as_inf(expr):
    """``expr`` with exact numbers beyond the double range (a mass of 1e308 times g = 1e308)
    replaced by ±inf, as float arithmetic would give, instead of an OverflowError when
    evaluated; the non-finite result is then reported by the checks of M, Q, A, b."""
    expr = sp.sympify(expr)
    huge = {x: sp.sign(x) * sp.oo for x in atoms_of([expr], sp.Rational) if abs(x) > _LARGEST}
    return replaced([expr], huge)[0] if huge else expr
