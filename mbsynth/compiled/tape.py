"""Every shared structure on one compiled function: its expressions as a tape.

structures.py evaluates the instances of one constraint or part structure together. Rather
than generating and compiling a numba function per structure (a second or more each: the
cold cost of a new model, paid again for every structure it brings), ``tape(args, forms)``
writes the structure's expressions, their common subexpressions once (sympy ``cse``), as a
list of operations on registers (a ``Taped``), and ``run`` — one numba function, compiled
once with the rest of the compiled path — reads those lists. A ``Program`` holds the tapes
of several structures, each with its instances, and evaluates them all in one call
(grouped.Batch: every shared structure of a model's constraints or parts):

    program(t, q, qd, p, values, out)
        for each structure g, for each of its instances m: out[dest of output k at m] = its
        expression k, coordinate slot j read from q[columns[j, m]] (velocities from qd),
        parameters from p, constant j from values (its rows × members, flat), number j from
        fixed[j, m]

An operation writes ``operands[:, i] = (destination, a, b, c)``: registers, or an index into
the arguments or ``numbers``. Each register is written once, so the operations whose operands
are all ready may run in any order: the tape groups them by level (the longest chain of
operations before them) and, within a level, by kind, and ``run`` reads each group
``batches[k] = (kind, first, stop)`` as one loop of that one operation: a dispatch per
group, not per operation, and the same values in the same registers as the operations one by
one. Piecewise expressions evaluate every branch and select (as numpy does), comparisons give
1.0 or 0.0. An expression of a kind the tape does not know raises ``Unsupported``
(structures.py then compiles the structure on its own).
"""

import functools
import math
from typing import NamedTuple

import numpy as np
import sympy as sp
from numba import njit

from ..symbolic.derive import beyond_double_as_inf

(T, Q, QD, P, VALUE, FIXED, NUMBER, OUT, ADD, SUB, MUL, DIV, NEG, SQUARE, POWI, POW, SQRT, SIN, COS, TAN, ASIN,
 ACOS, ATAN, ATAN2, SINH, COSH, TANH, EXP, LOG, ABS, SIGN, FLOOR, CEIL, MAX, MIN, LT, LE, EQ, NE, AND, OR, NOT,
 SELECT) = range(43)

READS = (T, Q, QD, P, VALUE, FIXED)  # the argument each slot group of a structure is read from
ARITY = {**dict.fromkeys(range(SELECT + 1), 1), ADD: 2, SUB: 2, MUL: 2, DIV: 2, POW: 2, ATAN2: 2, MAX: 2, MIN: 2,
         LT: 2, LE: 2, EQ: 2, NE: 2, AND: 2, OR: 2, SELECT: 3}  # the registers an operation reads (from a)
FUNCTIONS = {sp.sin: SIN, sp.cos: COS, sp.tan: TAN, sp.asin: ASIN, sp.acos: ACOS, sp.atan: ATAN, sp.sinh: SINH,
             sp.cosh: COSH, sp.tanh: TANH, sp.exp: EXP, sp.log: LOG, sp.Abs: ABS, sp.sign: SIGN, sp.floor: FLOOR,
             sp.ceiling: CEIL}
RELATIONS = {sp.StrictLessThan: (LT, False), sp.LessThan: (LE, False), sp.StrictGreaterThan: (LT, True),
             sp.GreaterThan: (LE, True), sp.Equality: (EQ, False), sp.Unequality: (NE, False)}


class Unsupported(Exception):
    """An expression the tape has no operation for."""


class Taped(NamedTuple):
    """A structure's tape as ``run`` reads it: its operation groups (kind, first, stop), their
    operands (rows: destination, a, b, c), its numbers and its count of registers."""

    batches: np.ndarray
    operands: np.ndarray
    numbers: np.ndarray
    size: int


class Program:
    """The tapes of several structures, each over its own instances, evaluated by one call.

    ``groups``: per structure (its Taped, columns (coordinate slots × members), its count of
    constant rows, fixed (number slots × members), dest (outputs × members): where in ``out``
    each output of each member goes). ``program(t, q, qd, p, values, out)``: ``values`` the
    constants of every structure in turn, each (rows × members) flattened row by row
    (``value_slices`` says where each lies)."""

    def __init__(self, groups):
        tapes = [taped for taped, *_ in groups]
        members = [where.shape[1] for *_, where in groups]
        # per structure, how much of each flat array it takes; where it starts is the sum of those before
        sizes = np.array([(len(taped.batches), taped.operands.shape[1], len(taped.numbers), np.size(cols),
                           rows * n, np.size(fix), np.size(where))
                          for (taped, cols, rows, fix, where), n in zip(groups, members)], dtype=np.int64).reshape(-1, 7)
        starts = np.cumsum(sizes, axis=0) - sizes
        batch, operand, number, column, value, fix_at, dest_at = starts.T
        plan = np.column_stack([batch, batch + sizes[:, 0], members, column, value, fix_at, number, dest_at])
        self.value_slices = [slice(a, a + size) for a, size in zip(value.tolist(), sizes[:, 4].tolist())]
        self.values_size = int(sizes[:, 4].sum())
        shifted = [taped.batches + np.array([0, k, k]) for taped, k in zip(tapes, operand.tolist())]

        def joined(arrays, dtype):
            return np.ascontiguousarray(np.concatenate([np.zeros(0, dtype)] + [np.ravel(x) for x in arrays]), dtype)
        self.call = functools.partial(
            run, np.ascontiguousarray(plan, dtype=np.uint64).reshape(-1, 8),
            np.concatenate([np.zeros((0, 3), np.int64)] + shifted),
            np.ascontiguousarray(np.concatenate([np.zeros((4, 0), np.uint64)] + [t.operands for t in tapes], axis=1)),
            joined([t.numbers for t in tapes], float), max([t.size for t in tapes], default=1),
            joined([cols for _, cols, *_ in groups], np.uint64), joined([fix for *_, fix, _ in groups], float),
            joined([where for *_, where in groups], np.uint64))

    def __call__(self, t, q, qd, p, values, out):
        self.call(t, q, qd, p, values, out)


class Tape:
    """The operations of one structure, in the order written (``arrays``: as ``run`` reads them)."""

    def __init__(self):
        self.code, self.operands, self.numbers = [], [], []
        self.size = 0
        self.made = {}  # expression -> its register

    def emit(self, op, a=0, b=0, c=0):
        """A new register holding ``op`` of (a, b, c)."""
        self.code.append(op)
        self.operands.append((self.size, a, b, c))
        self.size += 1
        return self.size - 1

    def number(self, value):
        self.numbers.append(float(value))
        return self.emit(NUMBER, len(self.numbers) - 1)

    def arrays(self):
        """(batches, operands, numbers, size) of a Taped: the operations grouped by (level,
        kind), the outputs last; their operands a row each of destinations, a, b and c
        (unsigned: no index wraps around)."""
        level = np.zeros(self.size, dtype=np.int64)  # each register's: 0 for the reads, else 1 + its inputs' highest
        for op, (d, a, b, c) in zip(self.code, self.operands):
            inputs = () if op in READS or op == NUMBER else (b,) if op == OUT else (a, b, c)[:ARITY[op]]
            level[d] = 1 + max((level[r] for r in inputs), default=-1)
        last = int(level.max(initial=0)) + 1
        keys = [(last if op == OUT else int(level[d]), op) for op, (d, *_) in zip(self.code, self.operands)]
        order = sorted(range(len(keys)), key=keys.__getitem__)
        batches = []  # [kind, first, stop] of each run of equal keys in ``order``
        for n, i in enumerate(order):
            if n == 0 or keys[i] != keys[order[n - 1]]:
                batches.append([keys[i][1], n, n])
            batches[-1][2] = n + 1
        return (np.array(batches, dtype=np.int64).reshape(-1, 3),
                np.ascontiguousarray(np.array([self.operands[i] for i in order], dtype=np.uint64).reshape(-1, 4).T),
                np.array(self.numbers + [0.0]), max(self.size, 1))


def tape(args, forms):
    """The Taped of ``forms`` in the slots ``args`` = (t, q slots, q̇ slots, parameter slots,
    constant slots, number slots)."""
    t, *groups = args
    written = Tape()
    reads = {t: (T, 0)}
    for op, slots in zip(READS[1:], groups):
        reads.update({s: (op, j) for j, s in enumerate(slots)})
    steps, results = sp.cse([beyond_double_as_inf(sp.sympify(e)) for e in forms],
                            symbols=sp.numbered_symbols("_x"), order="none")
    for symbol, expr in steps:
        written.made[symbol] = _register(written, expr, reads)
    for k, expr in enumerate(results):
        written.emit(OUT, k, _register(written, expr, reads))
    return Taped(*written.arrays())


def _register(written, expr, reads):
    """The register of ``expr``, its operations written first (each subexpression once)."""
    found = written.made.get(expr)
    if found is None:
        found = written.made[expr] = _write(written, expr, reads)
    return found


def _write(written, expr, reads):
    arg = lambda e: _register(written, e, reads)  # noqa: E731
    if expr in reads:
        op, j = reads[expr]
        return written.emit(op, j)
    if expr is sp.true or expr is sp.false:
        return written.number(expr is sp.true)
    if expr.is_Number or expr.is_NumberSymbol:
        return written.number(_float(expr))
    if expr.is_Add:
        return _sum(written, expr.args, arg)
    if expr.is_Mul:
        return _product(written, expr, arg)
    if expr.is_Pow:
        return _power(written, expr.base, expr.exp, arg)
    if expr.func in FUNCTIONS and len(expr.args) == 1:
        return written.emit(FUNCTIONS[expr.func], arg(expr.args[0]))
    if expr.func == sp.atan2:
        return written.emit(ATAN2, arg(expr.args[0]), arg(expr.args[1]))
    if expr.func in (sp.Max, sp.Min):
        return _fold(written, MAX if expr.func == sp.Max else MIN, [arg(x) for x in expr.args])
    if type(expr) in RELATIONS:
        op, swapped = RELATIONS[type(expr)]
        a, b = arg(expr.lhs), arg(expr.rhs)
        return written.emit(op, *((b, a) if swapped else (a, b)))
    if isinstance(expr, (sp.And, sp.Or)):
        return _fold(written, AND if isinstance(expr, sp.And) else OR, [arg(x) for x in expr.args])
    if isinstance(expr, sp.Not):
        return written.emit(NOT, arg(expr.args[0]))
    if isinstance(expr, sp.Piecewise):
        return _piecewise(written, expr, arg)
    raise Unsupported(f"{type(expr).__name__}: {expr}")


def _float(number):
    """A sympy number as a float (±inf, NaN for the infinities and NaN)."""
    if number is sp.zoo or number is sp.nan:
        return math.nan
    if number in (sp.oo, -sp.oo):
        return math.inf if number is sp.oo else -math.inf
    return float(number)


def _fold(written, op, registers):
    result = registers[0]
    for r in registers[1:]:
        result = written.emit(op, result, r)
    return result


def _sum(written, terms, arg):
    """A sum: a term with a negative coefficient (after the first) subtracted."""
    result = arg(terms[0])
    for term in terms[1:]:
        negative = term.as_coeff_Mul()[0] < 0
        result = written.emit(SUB if negative else ADD, result, arg(-term if negative else term))
    return result


def _product(written, expr, arg):
    """A product: −x as NEG; factors with a negative integer power as one division."""
    coefficient, factors = expr.as_coeff_mul()
    above = [f for f in factors if not (f.is_Pow and f.exp.is_Integer and f.exp < 0)]
    below = [f.base ** -f.exp for f in factors if f not in above]
    registers = [arg(f) for f in above]
    if coefficient not in (1, -1):
        registers.insert(0, arg(coefficient))
    result = _fold(written, MUL, registers) if registers else written.number(1.0)
    if below:
        result = written.emit(DIV, result, _fold(written, MUL, [arg(f) for f in below]))
    return written.emit(NEG, result) if coefficient == -1 else result


def _power(written, base, exponent, arg):
    if exponent == 2:
        return written.emit(SQUARE, arg(base))
    if exponent.is_Integer and exponent > 0:
        return written.emit(POWI, arg(base), int(exponent))
    if exponent.is_Integer:
        return written.emit(DIV, written.number(1.0), _power(written, base, -exponent, arg))
    if exponent == sp.Rational(1, 2):
        return written.emit(SQRT, arg(base))
    if exponent == -sp.Rational(1, 2):
        return written.emit(DIV, written.number(1.0), written.emit(SQRT, arg(base)))
    return written.emit(POW, arg(base), arg(exponent))


def _piecewise(written, expr, arg):
    """Every branch evaluated, the first whose condition holds selected (NaN where none)."""
    result = written.number(math.nan)
    for value, condition in reversed(expr.args):
        if condition is sp.true:
            result = arg(value)
        elif condition is not sp.false:
            result = written.emit(SELECT, arg(condition), arg(value), result)
    return result


@njit(cache=True, error_model="numpy", nogil=True)
def run(plan, batches, operands, numbers, size, columns, fixed, dest, t, q, qd, p, values, out):
    """``Program``'s call: for each structure g (``plan[g]`` = its first and stop batch, its
    count of members and where its columns, values, fixed, numbers and dest start), its
    tape read for each of its members."""
    r = np.empty(size)
    d, a, b, c = operands[0], operands[1], operands[2], operands[3]
    for g in range(plan.shape[0]):
        k0, k1, n, col, val, fix, num, at = (plan[g, 0], plan[g, 1], plan[g, 2], plan[g, 3], plan[g, 4], plan[g, 5],
                                             plan[g, 6], plan[g, 7])
        for m in range(n):
            for k in range(k0, k1):
                op, first, stop = batches[k, 0], batches[k, 1], batches[k, 2]
                if op == MUL:
                    for i in range(first, stop):
                        r[d[i]] = r[a[i]] * r[b[i]]
                elif op == ADD:
                    for i in range(first, stop):
                        r[d[i]] = r[a[i]] + r[b[i]]
                elif op == SUB:
                    for i in range(first, stop):
                        r[d[i]] = r[a[i]] - r[b[i]]
                elif op == OUT:
                    for i in range(first, stop):
                        out[dest[at + a[i] * n + m]] = r[b[i]]
                elif op == NEG:
                    for i in range(first, stop):
                        r[d[i]] = -r[a[i]]
                elif op == SQUARE:
                    for i in range(first, stop):
                        r[d[i]] = r[a[i]] * r[a[i]]
                elif op == Q:
                    for i in range(first, stop):
                        r[d[i]] = q[columns[col + a[i] * n + m]]
                elif op == QD:
                    for i in range(first, stop):
                        r[d[i]] = qd[columns[col + a[i] * n + m]]
                elif op == NUMBER:
                    for i in range(first, stop):
                        r[d[i]] = numbers[num + a[i]]
                elif op == P:
                    for i in range(first, stop):
                        r[d[i]] = p[a[i]]
                elif op == FIXED:
                    for i in range(first, stop):
                        r[d[i]] = fixed[fix + a[i] * n + m]
                elif op == VALUE:
                    for i in range(first, stop):
                        r[d[i]] = values[val + a[i] * n + m]
                elif op == DIV:
                    for i in range(first, stop):
                        r[d[i]] = r[a[i]] / r[b[i]]
                elif op == SIN:
                    for i in range(first, stop):
                        r[d[i]] = math.sin(r[a[i]])
                elif op == COS:
                    for i in range(first, stop):
                        r[d[i]] = math.cos(r[a[i]])
                else:
                    for i in range(first, stop):
                        r[d[i]] = _rare(op, r, np.int64(a[i]), np.int64(b[i]), np.int64(c[i]), t)


@njit(cache=True, error_model="numpy", nogil=True)
def _rare(op, r, a, b, c, t):
    """The value of the operations ``run`` does not test for first."""
    x = r[a]
    if op == T:
        return t
    if op == POWI:
        return x ** b
    if op == POW:
        return x ** r[b]
    if op == SQRT:
        return math.sqrt(x) if x >= 0 else math.nan
    if op == ATAN2:
        return math.atan2(x, r[b])
    if op == TAN:
        return math.tan(x)
    if op == ASIN:
        return math.asin(x) if -1 <= x <= 1 else math.nan
    if op == ACOS:
        return math.acos(x) if -1 <= x <= 1 else math.nan
    if op == ATAN:
        return math.atan(x)
    if op == SINH:
        return math.sinh(x)
    if op == COSH:
        return math.cosh(x)
    if op == TANH:
        return math.tanh(x)
    if op == EXP:
        return math.exp(x)
    if op == LOG:
        return math.log(x) if x > 0 else (-math.inf if x == 0 else math.nan)
    if op == ABS:
        return abs(x)
    if op == SIGN:
        return math.nan if x != x else (1.0 if x > 0 else (-1.0 if x < 0 else 0.0))
    if op == FLOOR:
        return np.floor(x)
    if op == CEIL:
        return np.ceil(x)
    if op == MAX:
        return x if (x > r[b] or x != x) else r[b]
    if op == MIN:
        return x if (x < r[b] or x != x) else r[b]
    if op == LT:
        return 1.0 if x < r[b] else 0.0
    if op == LE:
        return 1.0 if x <= r[b] else 0.0
    if op == EQ:
        return 1.0 if x == r[b] else 0.0
    if op == NE:
        return 1.0 if x != r[b] else 0.0
    if op == AND:
        return 1.0 if (x != 0 and r[b] != 0) else 0.0
    if op == OR:
        return 1.0 if (x != 0 or r[b] != 0) else 0.0
    if op == NOT:
        return 1.0 if x == 0 else 0.0
    if op == SELECT:
        return r[b] if x != 0 else r[c]
    return math.nan
