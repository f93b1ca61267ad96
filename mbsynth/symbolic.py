"""Symbolic derivations done once per model, and their compilation to numpy.

- ``lagrange(T, V, F, q, qd, t)``: the unconstrained equation ``M q̈ = Q`` (2.1)
  of a part given by its kinetic energy T, potential energy V and generalized
  forces F, from Lagrange's equations.
- ``differentiate(phi, q, qd, t)``: a constraint ``phi = 0`` differentiated to
  the row ``A q̈ = b`` (2.4), once if phi contains velocities, twice if not.
- ``generalized_force(V, efforts, q, qd)``: Q of a potential and (effort, rate) pairs.
- ``compile_function(args, exprs)``: one fast numpy function for many expressions.
"""

import functools

import numpy as np
import sympy as sp

T_SYMBOL = sp.Symbol("t")
_LARGEST = sp.Float(np.finfo(float).max)
# pi and e as numpy floats, so that all arithmetic of a compiled expression is numpy's:
# Python floats raise on overflow and division by zero ((2*pi + 1e308)**251, 1/(1 - t) at
# t = 1) where numpy's give inf, which the checks of M, Q, A, b then report
_FLOAT64 = {"pi": np.float64(np.pi), "e": np.float64(np.e)}
SIMPLIFY_MAX_OPS = 60  # sympy.simplify takes seconds beyond this, growing fast (nested sin, exp)


def lagrange(T, V, F, q, qd, t=T_SYMBOL):
    """M and Q of (2.1) from Lagrange's equations d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q = F.

    Expanding d/dt ∂T/∂q̇ = (∂²T/∂q̇²) q̈ + (∂²T/∂q̇∂q) q̇ + ∂²T/∂q̇∂t gives
    M = ∂²T/∂q̇², Q = F + ∂T/∂q − ∂V/∂q − (∂²T/∂q̇∂q) q̇ − ∂²T/∂q̇∂t.
    Each entry is simplified when it is small (``tidy``).
    """
    q, qd = sp.Matrix(q), sp.Matrix(qd)
    p = sp.Matrix([T]).jacobian(qd).T  # generalized momenta ∂T/∂q̇
    M = p.jacobian(qd)
    Q = (sp.Matrix(F) + sp.Matrix([T - V]).jacobian(q).T
         - p.jacobian(q) * qd - p.diff(t))
    return M.applyfunc(tidy), Q.applyfunc(tidy)


def tidy(expr, max_ops=SIMPLIFY_MAX_OPS):
    """sympy.simplify for expressions small enough to be worth it (it is slow on big ones)."""
    return sp.simplify(expr) if sp.count_ops(expr) <= max_ops else expr


def jacobian(exprs, symbols):
    """∂exprs/∂symbols (a len(exprs) × len(symbols) matrix), differentiating each
    expression only by the symbols it contains: a model has hundreds of coordinates and
    a joint's rows involve fourteen."""
    exprs, symbols = [sp.sympify(e) for e in exprs], list(symbols)
    out = sp.zeros(len(exprs), len(symbols))
    for i, e in enumerate(exprs):
        free = e.free_symbols
        for j, s in enumerate(symbols):
            if s in free:
                out[i, j] = e.diff(s)
    return out


def time_derivative(expr, q, qd, t=T_SYMBOL):
    """d/dt of an expression of (q, t) along the motion: (∂e/∂q) q̇ + ∂e/∂t."""
    return (jacobian([expr], q) * sp.Matrix(qd))[0] + sp.diff(expr, t)


def generalized_force(V, efforts, q, qd):
    """Q = −∂V/∂q + Σ effort ∂rate/∂q̇ (virtual power; each rate linear in q̇), a column over q."""
    Q = -jacobian([V], q).T
    for effort, rate in efforts:
        Q += sp.sympify(effort) * jacobian([rate], qd).T
    return Q


def differentiate(phi, q, qd, t=T_SYMBOL):
    """Row (a, b, phidot) of A q̈ = b (2.4) for the constraint phi(q, q̇, t) = 0.

    A position-level phi(q, t) is differentiated twice (phidot = d phi/dt); a
    velocity-level phi(q, q̇, t) once (phidot is phi itself). With ψ the
    velocity-level form, ψ̇ = (∂ψ/∂q̇) q̈ + (∂ψ/∂q) q̇ + ∂ψ/∂t = 0, so
    a = ∂ψ/∂q̇ and b = −(∂ψ/∂q) q̇ − ∂ψ/∂t.
    """
    velocity_level = bool(set(qd) & phi.free_symbols)
    psi = phi if velocity_level else time_derivative(phi, q, qd, t)
    a = jacobian([psi], qd)
    b = -(jacobian([psi], q) * sp.Matrix(qd))[0] - sp.diff(psi, t)
    return a, b, psi


def compile_function(args, exprs):
    """A numpy function of ``args`` returning a tuple of float arrays, one per entry of
    ``exprs`` (scalars, vectors or matrices), with common subexpressions shared."""
    shapes = [sp.Matrix(e).shape if isinstance(e, sp.MatrixBase) else () for e in exprs]
    flat = [x for e in exprs for x in (e if isinstance(e, sp.MatrixBase) else [e])]
    if not flat:
        def empty(*_):
            return tuple(np.zeros(s) for s in shapes)
        return empty
    raw = _lambdify(_frozen(args), tuple(flat))
    sizes = [int(np.prod(s)) for s in shapes]
    splits = np.cumsum(sizes)[:-1]

    def evaluate(*values):
        values = [np.float64(v) if isinstance(v, (int, float)) else v for v in values]
        with np.errstate(all="ignore"):  # NaN and inf are reported by the checks of M, Q, A, b
            out = np.asarray(raw(*values), dtype=float)
        return tuple(part.reshape(shape) for part, shape in zip(np.split(out, splits), shapes))

    return evaluate


@functools.lru_cache(maxsize=1024)
def _lambdify(args, flat):
    """The numpy function of (args) -> [flat], made once per distinct (args, flat): models
    loaded again (a sweep's workers, a file checked then simulated) reuse it."""
    return sp.lambdify(args, [_beyond_double_as_inf(x) for x in flat], modules=[_FLOAT64, "numpy"], cse=True,
                       dummify=True)


def _frozen(args):
    """``args`` with its lists made tuples (hashable), nested."""
    return tuple(_frozen(a) if isinstance(a, (list, tuple)) else a for a in args)


def _beyond_double_as_inf(expr):
    """``expr`` with exact numbers beyond the double range (a mass of 1e308 times g = 1e308)
    replaced by ±inf, as float arithmetic would give, instead of an OverflowError when
    evaluated; the non-finite result is then reported by the checks of M, Q, A, b."""
    huge = {x: sp.sign(x) * sp.oo for x in sp.sympify(expr).atoms(sp.Rational) if abs(x) > _LARGEST}
    return sp.sympify(expr).xreplace(huge) if huge else expr
