"""Closing models with massless parts: the force balances of Result 3.

When ``[M; A]`` has a null vector w, premultiplying (2.5) by wᵀ gives
wᵀMq̈ = 0 = wᵀ(Q + C) (using (2.6), since Aw = 0): the applied forces along w
must balance, or no motion exists. Such a balance is exactly what the paper adds
by hand in example 3: (5.40) k1 x̄1 = k2 q̄2 when m1 = 0, (5.49) k2 q̄2 = 0 when
m2 = 0. Where the balance vanishes identically (example 2's massless particle,
(5.23)) the direction is simply free. ``balances`` derives them symbolically;
``append_balances`` appends the non-trivial ones as constraints (``balances: auto``).
"""

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import sympy as sp

from .angle_singularity import AngleParts
from .constraints.base import Constraint
from .data import workspace
from ..core.equations import rank_report
from ..core.errors import ModelError
from ..symbolic.derive import T_SYMBOL, exceeds, tidy
from .system import AppendedBalance
from ..core.tolerances import BALANCE_ENTRY_ZERO, BALANCE_ZERO_RTOL, RATIONAL_TOL, READABLE_DROP

SAMPLES = 8


@dataclass(frozen=True)
class Balance:
    """One indeterminate direction w and its balance wᵀ(Q + C) = 0.

    ``direction``: {coordinate: component} at the diagnosed state, largest component +1.
    ``expression``: wᵀ(Q + C) in the model's symbols (0 when identically zero: a free
    direction). ``state_dependent``: w itself changes with the state, so the balance
    holds along the motion only while the null space keeps its form. ``value``: wᵀ(Q + C)
    at the diagnosed state, w scaled as ``direction`` (printed for an expression too large
    to write).
    """

    direction: dict
    expression: sp.Expr
    state_dependent: bool
    value: float = 0.0

    @property
    def free(self):
        return self.expression == 0

    @property
    def equation(self):
        """wᵀ(Q + C) = 0 written out; beyond SYMBOLIC_SIZE_MAX nodes, its value at the
        diagnosed state instead (``numeric``)."""
        return self.numeric if exceeds(self.expression, SYMBOLIC_SIZE_MAX) else f"{sp.sstr(self.expression)} = 0"

    @property
    def readable_equation(self):
        """``equation`` as a person reads it (``readable``)."""
        return self.numeric if exceeds(self.expression, SYMBOLIC_SIZE_MAX) else f"{readable(self.expression)} = 0"

    @property
    def numeric(self):
        return (f"wᵀ(Q + C) = 0 along the direction, {self.value:.6g} at this state (its expression, of more than "
                f"{SYMBOLIC_SIZE_MAX} symbols and operations, is not written out)")


def balances(data, t=0.0, q=None, qd=None):
    """The balances of every indeterminate direction of the model of ``data`` (a Data, or a
    model: its default-path Data) at its parameter values (none when unique), but
    those of a part's angles at their singular position (angle_singularity.py: the
    coordinates' fault, no balance closes them).

    Where [M; A] (with the parameter values substituted) does not depend on the state,
    its null space is found exactly (sympy). Otherwise, or where the exact dimension
    differs from the numeric one at (t, q, q̇), the numeric null vectors at that state
    are used and the balances are marked state dependent: they hold at this state and
    along the motion only while the null space keeps its form.
    """
    data = workspace(data)
    system = data.model
    q0, qd0 = system.initial_state()
    q = q0 if q is None else np.asarray(q, dtype=float)
    qd = qd0 if qd is None else np.asarray(qd, dtype=float)
    arrays = data.evaluate(t, q, qd)
    numeric = AngleParts(system).set_aside(q, rank_report(arrays.M, arrays.A).nullspace)[1]
    if numeric.shape[1] == 0:
        return []  # before the sympy form of the model (costly on a robot)
    values = {sp.Symbol(k): sp.nsimplify(v, rational=True) for k, v in data.parameters.items()}
    M, Q, A, _, C = system.symbolic()
    force = Q + C
    state = {s: v for s, v in zip(system.q_symbols + system.qd_symbols, np.concatenate([q, qd]))}
    state[T_SYMBOL] = t
    dynamic = set(system.q_symbols) | set(system.qd_symbols) | {T_SYMBOL}
    Mhat = M.col_join(A).subs(values)
    exact = not Mhat.free_symbols & dynamic and not exceeds(Mhat, SYMBOLIC_SIZE_MAX)
    symbolic_w = Mhat.nullspace(simplify=True) if exact else []
    if len(symbolic_w) == numeric.shape[1]:
        W, state_dependent = sp.Matrix.hstack(*symbolic_w), False
    else:
        W, state_dependent = sp.Matrix(_rational_rows(numeric.T)).T, True
    free, balanced = _separate(np.array(W.evalf(), dtype=float), system, q, qd, t)
    result = []
    for combos, is_free in ((free, True), (balanced, False)):
        if not combos:
            continue
        for w in _canonical(W * sp.Matrix(combos).T, state, dynamic):
            expression = sp.S.Zero if is_free else tidy((w.T * force)[0])  # tidy: bounded (derive.py)
            vector = np.array(w.subs(state).evalf(), dtype=float).ravel()
            vector /= vector[np.argmax(np.abs(vector))]
            entries = {c: float(v) for c, v in zip(system.coordinates, vector) if abs(v) > BALANCE_ENTRY_ZERO}
            result.append(Balance(entries, expression, state_dependent, float(vector @ (arrays.Q + arrays.C))))
    return result


SYMBOLIC_SIZE_MAX = 400  # nodes of an expression (or of a matrix's non-numeric entries) beyond which it is not
# factored, put through a simplifying nullspace or printed (a flexible body's balance has 50,000 nodes)


READABLE_DIGITS = 6  # significant digits of the numbers in a printed balance


def readable(expression):
    """``expression`` printed for a person: factored (a polynomial that is a product), each sum factor scaled
    so that its largest coefficient is 1, the terms of a sum below READABLE_DROP times its
    largest left out, numbers rounded to READABLE_DIGITS significant digits — the rationals
    of a numeric null vector (state-dependent directions) come out as short decimals."""
    small = not exceeds(expression, SYMBOLIC_SIZE_MAX)
    factored = sp.factor(expression) if small and expression.is_polynomial() else expression
    if sum(not factor.is_Number for factor in sp.Mul.make_args(factored)) < 2:  # no product to show
        factored = expression
    if factored.is_Add:
        return sp.sstr(_kept_terms(sp.Add.make_args(factored)), full_prec=False)
    coefficient, factors = sp.S.One, []
    for factor in sp.Mul.make_args(factored):
        base, exponent = factor.as_base_exp()
        if factor.is_Number:
            coefficient *= factor
        elif base.is_Add and exponent.is_Integer:
            terms = sp.Add.make_args(base)
            largest = max((term.as_coeff_Mul()[0] for term in terms), key=abs)
            coefficient *= largest**exponent
            base = _kept_terms([term / largest for term in terms])
            factors.append(base if exponent == 1 else sp.Pow(base, exponent, evaluate=False))
        else:
            factors.append(_rounded(factor))
    if coefficient != 1 or not factors:
        factors.insert(0, _rounded(coefficient))
    return sp.sstr(sp.Mul(*factors, evaluate=False) if len(factors) > 1 else factors[0], full_prec=False)


def _kept_terms(terms):
    """The sum of ``terms``, rounded, without those whose coefficient is below READABLE_DROP
    times the largest."""
    coefficients = [abs(term.as_coeff_Mul()[0]) for term in terms]
    kept = [_rounded(term) for term, c in zip(terms, coefficients) if c >= READABLE_DROP * max(coefficients)]
    return sp.Add(*kept, evaluate=False) if len(kept) > 1 else kept[0]


def _rounded(expression):
    """``expression`` with its numbers other than small integers as floats of READABLE_DIGITS digits."""
    small = 10**READABLE_DIGITS
    return expression.xreplace({x: sp.Float(x, READABLE_DIGITS) for x in expression.atoms(sp.Number)
                                if not (x.is_Integer and abs(x) < small)})


def _separate(W, system, q, qd, t):
    """Split the span of the balances g = Wᵀ(Q + C) (W: the null vectors, numbers) into
    combinations that vanish identically (free directions) and a basis of the rest, by
    sampling Q + C numerically at random states (``System.evaluate``)."""
    rng = np.random.default_rng(0)
    samples = []
    for _ in range(SAMPLES):
        x = system.evaluate(t + rng.normal(), q + rng.normal(size=q.size), qd + rng.normal(size=qd.size))
        samples.append(W.T @ (x.Q + x.C))
    G = np.array(samples)  # SAMPLES x r
    scale = np.abs(G).max()
    if scale == 0:
        return _rational_rows(np.eye(G.shape[1])), []
    _, s, vt = np.linalg.svd(G / scale)
    rank = int(np.sum(s > BALANCE_ZERO_RTOL))
    return _rational_rows(vt[rank:]), _rational_rows(vt[:rank])


def _rational_rows(rows):
    return [[sp.nsimplify(x, rational=True, tolerance=RATIONAL_TOL) for x in row] for row in rows]


def _canonical(D, state, dynamic):
    """The columns of D recombined so that each is +1 at a coordinate of its own where the
    others are 0 (a reduced echelon form, pivots chosen by QR with column pivoting at the
    state): a direction of three free coordinates comes out as the three unit vectors, not
    as an arbitrary orthonormal mixture. Exact when D is constant."""
    numeric = np.array(D.subs(state).evalf(), dtype=float)
    pivots = sorted(scipy.linalg.qr(numeric.T, pivoting=True)[2][:D.shape[1]])
    if D.free_symbols & dynamic:
        D = sp.Matrix(_rational_rows((numeric @ np.linalg.inv(numeric[pivots, :])).T)).T
    else:
        D = D * D.extract(pivots, list(range(D.shape[1]))).inv()
    return [D[:, j] for j in range(D.shape[1])]


def append_balances(system, max_rounds=None):
    """Append every non-trivial balance as a constraint until the motion is unique or
    only free directions are left (``balances: auto``). Returns a new System."""
    for round_ in range(max_rounds or system.n):
        needed = [bal for bal in balances(system) if not bal.free]
        if not needed:
            return system
        extra, notes = [], []
        for bal in needed:
            name = f"balance_{len(system.appended_balances) + len(extra) + 1}"
            extra.append(_as_constraint(system, name, bal))
            notes.append(AppendedBalance(name, bal.equation, bal.direction, bal.state_dependent))
        before = rank_report(*_MA(system)).rank_Mhat
        system = system.with_constraints(extra, notes)
        if rank_report(*_MA(system)).rank_Mhat == before:
            raise ModelError(f"model '{system.name}': balances {[b.equation for b in needed]} "
                             "do not determine the indeterminate accelerations")
    return system


def _MA(system):
    arrays = system.evaluate(0.0, *system.initial_state())
    return arrays.M, arrays.A


def _as_constraint(system, name, bal):
    expression = bal.expression
    dynamic = set(system.q_symbols) | set(system.qd_symbols)
    if not expression.free_symbols & dynamic:
        raise ModelError(f"model '{system.name}': the force along {bal.direction} is "
                         f"{sp.sstr(expression)}, which involves no coordinate, and no mass resists "
                         "that direction: the model admits no motion")
    args = (system.q_symbols, system.qd_symbols, system.parameter_symbols)
    if expression.free_symbols & set(system.qd_symbols):
        return Constraint.nonholonomic(name, [expression], *args)
    return Constraint.holonomic(name, [expression], *args)
