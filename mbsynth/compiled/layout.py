"""What the compiled path computes where: a System turned, once, into index and number arrays.

Kernel nodes are the rigid bodies (with their own ``<body>.unit_quaternion`` row) and the
particles (their type's ``node``); kernel joints are the holonomic joints (of a kind whose
record says ``compiled``, core/joint_kinds.py) whose ends are nodes or the world and
whose frames are constant. A breadth-first search from the world (then from each body no
joint path reaches) picks each node's parent joint: those joints form the tree
(tree.py); the other kernel joints close loops, and their rows join the *extra rows*.

Everything else enters through ONE generated function (codegen.py) of (t, q, q̇, p):
the force elements' Q, every constraint's C, the M and Q of the other parts (their
coordinates are the *extra coordinates*), and the rows a, b of the other constraints
(extra rows too; rows that vanish identically are left out). ``build`` returns the Layout,
that function's expressions, in the order of its outputs: Q additions, C, M entries of
the extra coordinates, entries of extra rows, b of extra rows, inputs of the flexible
parts' kernel, φ of extra rows (for the relative drift off the manifold,
Engine.relative_drift), how many are φ, and the flexible parts (``Own``). A part with
``kernel_arrays`` (a flexible body) has its M (every entry, row by row) and Q among those
outputs as None: flexible.py's kernel writes them after the generated function, its gravity
vector read from the inputs.

Masses, inertias, gravity forces, frame offsets and rotations and rod lengths are the
*numbers* of a Layout, evaluated at the System's parameter values; every other array
depends only on the parts, the constraints and the parameters' names. ``with_parameters``
re-evaluates the numbers for a System that differs only in parameter values
(``System.with_parameters``) and shares the rest, so the compiled code is reused.
"""

from collections import deque
from typing import NamedTuple

import numpy as np
import sympy as sp

from ..core.joint_kinds import COMPONENT, KINDS, MAX_ROWS
from .banded import band_order
from .joints import PARTICLE, RIGID, WORLD
from .tree import GENERAL, RIGID_COMPONENTS, RIGID_INVARIANT
from .nodes import EXTRA_NODE, PARTICLE_NODE, RIGID_NODE

# a System with no kernel node is one Schur system (kernel.py), its extra coordinates and rows: up to this size it
# is dense (Jacobi's eigendecomposition, O(p³)); beyond it, where the extra coordinates' mass is diagonal, the
# rows' Schur matrix is banded (banded.py), else the System is left to the KKT path
DENSE_SCHUR_MAX = 64
# what a part is to the kernels is its type's ``node`` (nodes.py, model/parts/part_type.py): the model is read
# through its parts' and joints' attributes (``part_type.node``, ``joint_kind``, masses, frames), not their classes


def _node(part):
    """The kernel node kind of a part's type, None for the world (a joint's missing end)."""
    return None if part is None else part.part_type.node


class Own(NamedTuple):
    """A part whose M and Q flexible.py's kernel writes into the generated outputs: its first
    coordinate, the outputs of its M (row by row) and Q, of its gravity vector (inputs), and
    its arrays (axes, W, s0, K, D, S: the part's ``kernel_arrays``)."""

    start: int
    m0: int
    q0: int
    g0: int
    arrays: tuple


class Layout(NamedTuple):
    """Arrays read by the kernels (assembly.py, kernel.py). N nodes, K kernel joints."""

    node_kind: np.ndarray    # (N,) RIGID or PARTICLE
    node_q: np.ndarray       # (N,) first coordinate
    node_mass: np.ndarray    # (N,)
    node_mg: np.ndarray      # (N, 3) the gravity force m g
    node_J: np.ndarray       # (N, 3, 3) inertia about the centre of mass, body axes (0 for particles)
    node_v: np.ndarray       # (N,) unknowns per node: 6 (rigid, bodies.py) or 3
    node_k: np.ndarray       # (N,) rows of the joint to its parent (0 for a free root)
    node_yoff: np.ndarray    # (N,) offset of the node's block in tree vectors
    node_rows: np.ndarray    # (N,) first tree row of its parent joint
    node_parent: np.ndarray  # (N,) parent node, −1 for a root
    node_joint: np.ndarray   # (N,) kernel joint to its parent, −1 for a free root
    node_end: np.ndarray     # (N,) which end (0 = A, 1 = B) of that joint the node is
    node_transport: np.ndarray  # (N,) tree.GENERAL, RIGID_INVARIANT or RIGID_COMPONENTS
    order: np.ndarray        # (N,) parents before children
    joint_kinds: np.ndarray  # (K, 2) WORLD, RIGID or PARTICLE per end
    joint_start: np.ndarray  # (K, 2) first coordinate of each end's part
    joint_node: np.ndarray   # (K, 2) each end's node; the world's: N, its slot of Work.Rs
    joint_s: np.ndarray      # (K, 2, 3) frame offset in its part (world position for a world end)
    joint_R: np.ndarray      # (K, 2, 3, 3) frame rotation in its part
    joint_length: np.ndarray  # (K,) a distance joint's L (1 otherwise)
    joint_program: np.ndarray  # (K, 6, 3) row program (core/joint_kinds.py: a kind's program)
    joint_k: np.ndarray      # (K,)
    joint_row: np.ndarray    # (K,) the System's row of the joint's first row
    joint_xrow: np.ndarray   # (K,) first extra row of a loop joint, −1 for a tree joint
    joint_xseg: np.ndarray   # (K, 2) each end's place among a loop row's segments, −1 for the world
    x_coord: np.ndarray      # (n_x,) the System's coordinate of each extra coordinate
    xrow_row: np.ndarray     # (m_x,) the System's row of each extra row
    xseg_ptr: np.ndarray     # (m_x + 1,) segments (7 coefficients on one node) of each extra row
    xseg_node: np.ndarray    # (S,)
    gen_q: np.ndarray        # coordinate of each Q addition
    gen_c: np.ndarray        # coordinate of each C entry
    gen_mi: np.ndarray       # extra-coordinate pair of each M entry
    gen_mj: np.ndarray
    gen_arow: np.ndarray     # extra row of each row entry
    gen_aseg: np.ndarray     # its flat place in the segments (7 per segment), or −1
    gen_acol: np.ndarray     # its extra coordinate, or −1
    gen_brow: np.ndarray     # extra row of each b
    xa_ptr: np.ndarray       # (m_x + 1,) the extra coordinates each extra row touches (CSR: xa_col)
    xa_col: np.ndarray
    xc_ptr: np.ndarray       # (n_x + 1,) the extra rows that touch each extra coordinate (CSC: xc_row)
    xc_row: np.ndarray
    band_pos: np.ndarray     # (m_x,) each extra row's place in the banded Schur matrix (banded.py), or empty: dense
    band_width: np.ndarray   # (1,) that matrix's band width, or empty: dense
    quat_row: np.ndarray     # (N,) the System's row of a body's unit-norm row (−1 for particles)
    sizes: np.ndarray        # n, m, tree unknowns, tree rows


def _patterns(gen, rows, columns):
    """The entries of the extra rows on the extra coordinates (``gen_arow``, ``gen_acol``)
    as CSR by row (xa_ptr, xa_col) and CSC by coordinate (xc_ptr, xc_row), each index once."""
    pairs = sorted({(int(r), int(c)) for r, c in zip(gen["gen_arow"], gen["gen_acol"]) if c >= 0})
    by_column = sorted((c, r) for r, c in pairs)
    return dict(xa_ptr=_ints(np.searchsorted([r for r, _ in pairs], np.arange(rows + 1))),
                xa_col=_ints([c for _, c in pairs]),
                xc_ptr=_ints(np.searchsorted([c for c, _ in by_column], np.arange(columns + 1))),
                xc_row=_ints([r for _, r in by_column]))


def _diagonal(gen, columns):
    """Whether the extra coordinates' mass has an entry on each diagonal place and no other."""
    mi, mj = gen["gen_mi"], gen["gen_mj"]
    return bool((mi == mj).all()) and set(mi.tolist()) == set(range(columns))


def _ints(values, shape=None):
    a = np.array(values, dtype=np.int64)
    return a.reshape(shape) if shape is not None else a


class _Numbers:
    """Float values of parameter expressions at ``parameters`` ({name: value})."""

    def __init__(self, parameters):
        self.values = {sp.Symbol(k): float(v) for k, v in parameters.items()}

    def constant(self, expr):
        return not (sp.sympify(expr).free_symbols - set(self.values))

    def __call__(self, expr):
        """A 2-d array (1 × 1 for a scalar)."""
        matrix = expr if isinstance(expr, sp.MatrixBase) else sp.Matrix([[sp.sympify(expr)]])
        return np.array(matrix.xreplace(self.values).tolist(), dtype=float)


class _Symbols(_Numbers):
    """The names of the parameters that numbers depend on (``used``), each expression's free
    symbols recorded; zeros of its shape returned."""

    def __init__(self, parameters):
        super().__init__(parameters)
        self.used = set()

    def __call__(self, expr):
        matrix = expr if isinstance(expr, sp.MatrixBase) else sp.Matrix([[sp.sympify(expr)]])
        self.used |= {s.name for s in matrix.free_symbols if s in self.values}
        return np.zeros(matrix.shape)


def build(system):
    """(Layout, generated expressions, how many of the last are φ of extra rows, the
    flexible parts' ``Own``) of ``system``, or None when a joint has Coulomb friction (its C depends on q̈:
    system.motion iterates) or no part is a kernel node and the dense Schur system of its
    coordinates and rows would exceed DENSE_SCHUR_MAX."""
    if any(getattr(con, "coulomb", None) for con in system.constraints):
        return None
    number = _Numbers(system.parameters)
    starts = np.cumsum([0] + [len(p.coordinates) for p in system.parts])
    row_starts = np.cumsum([0] + [c.size for c in system.constraints])
    quat = {c.name: r for c, r in zip(system.constraints, row_starts) if c.name.endswith(".unit_quaternion")}
    nodes = [(part, int(start)) for part, start in zip(system.parts, starts)
             if (_node(part) == RIGID_NODE and f"{part.name}.unit_quaternion" in quat) or _node(part) == PARTICLE_NODE]
    if not nodes and system.n > DENSE_SCHUR_MAX and not all(part.kernel_arrays is None and part.M.is_diagonal()
                                                            for part in system.parts):
        return None  # its Schur system has at least its n coordinates, and cannot be banded
    node_of = {part.name: i for i, (part, _) in enumerate(nodes)}
    quat_rows = {quat[f"{part.name}.unit_quaternion"] for part, _ in nodes if _node(part) == RIGID_NODE}
    joints, others = [], []
    for con, row in zip(system.constraints, row_starts):
        if int(row) in quat_rows and con.size == 1:
            continue
        (joints if _kernel_joint(con, node_of, number) else others).append((con, int(row)))
    parent, pjoint, order = _tree(len(nodes), joints, node_of)
    found = _Builder(system, number, starts, nodes, node_of, quat, joints, others, parent, pjoint, order).layout()
    if not nodes and found[0].x_coord.size + found[0].xrow_row.size > DENSE_SCHUR_MAX and not found[0].band_width.size:
        return None
    return found


def _kernel_joint(con, node_of, number):
    kind = KINDS.get(getattr(con, "joint_kind", None))
    if kind is None or not kind.compiled:
        return False
    if any(part is not None and part.name not in node_of for part in con.parts):
        return False
    return all(number.constant(f.position) and number.constant(f.rotation) for f in con.frames)


def _tree(count, joints, node_of):
    """(parent node, parent joint, order): breadth-first from the world, then from each
    node no joint path reaches."""
    parent, pjoint = [-1] * count, [-1] * count
    seen, order = [False] * count, []
    neighbours = [[] for _ in range(count)]
    roots = []
    for j, (con, _) in enumerate(joints):
        ends = [None if p is None else node_of[p.name] for p in con.parts]
        if None in ends:
            roots.append((ends[1 - ends.index(None)], j))
        else:
            neighbours[ends[0]].append((ends[1], j))
            neighbours[ends[1]].append((ends[0], j))

    def grow(queue):
        while queue:
            i = queue.popleft()
            for child, j in neighbours[i]:
                if not seen[child]:
                    seen[child], parent[child], pjoint[child] = True, i, j
                    order.append(child)
                    queue.append(child)

    queue = deque()
    for i, j in roots:
        if not seen[i]:
            seen[i], pjoint[i] = True, j
            order.append(i)
            queue.append(i)
    grow(queue)
    for i in range(count):
        if not seen[i]:
            seen[i] = True
            order.append(i)
            grow(deque([i]))
    return parent, pjoint, order


def rigid_tree(L):
    """Whether ``L`` is rigid bodies on tree joints only: no joint with a particle end, no
    extra rows, no extra coordinates (the kernel then compiles without them: kernel.RIGID_TREE)."""
    return not (np.any(L.joint_kinds == PARTICLE) or L.xrow_row.size or L.x_coord.size)


def with_parameters(L, sources, parameters):
    """``L`` with the numbers at ``parameters`` ({name: value}; the System ``L`` was built
    from at other values), ``sources`` its nodes' parts and kernel joints (``sources``)."""
    return L._replace(**_numbers(*sources, _Numbers(parameters)))


def number_parameters(L, sources, parameters):
    """The names of the parameters that ``L``'s numbers (``_numbers``) depend on: parameter
    values that differ only in others share ``L`` as it is."""
    symbols = _Symbols(parameters)
    _numbers(*sources, symbols)
    return frozenset(symbols.used)


def sources(L, system):
    """(the parts of ``L``'s nodes, the constraints of its kernel joints) in ``system``."""
    starts = np.cumsum([0] + [len(p.coordinates) for p in system.parts])
    rows = np.cumsum([0] + [c.size for c in system.constraints])
    part_at = {int(s): part for part, s in zip(system.parts, starts)}
    con_at = {int(r): con for con, r in zip(system.constraints, rows)}
    return [part_at[int(c)] for c in L.node_q], [con_at[int(r)] for r in L.joint_row]


def _numbers(parts, joints, number):
    """The Layout's fields that depend on parameter values, for its nodes' ``parts`` and its
    kernel ``joints``: node_mass, node_mg, node_J, joint_s, joint_R, joint_length."""
    masses, mg, inertia = [], [], []
    for part in parts:
        if _node(part) == RIGID_NODE:
            masses.append(number(part.mass)[0, 0])
            inertia.append(number(part.inertia))
            mg.append(number(part.mass * part.gravity).ravel())
        else:
            masses.append(number(part.M[0, 0])[0, 0])
            inertia.append(np.zeros((3, 3)))
            mg.append(number(part.Q[:3, 0]).ravel())  # m g: the first three entries of Q, constant
    offsets, rotations, lengths = [], [], []
    for con in joints:
        for part, frame in zip(con.parts, con.frames):
            offsets.append(np.zeros(3) if _node(part) == PARTICLE_NODE else number(frame.position).ravel())
            rotations.append(number(frame.rotation))
        lengths.append(number(con.length)[0, 0] if KINDS[con.joint_kind].has_length else 1.0)
    N = len(parts)
    return dict(node_mass=np.array(masses, dtype=float), node_mg=np.array(mg, dtype=float).reshape(N, 3),
                node_J=np.array(inertia, dtype=float).reshape(N, 3, 3),
                joint_s=np.array(offsets, dtype=float).reshape(-1, 2, 3),
                joint_R=np.array(rotations, dtype=float).reshape(-1, 2, 3, 3),
                joint_length=np.array(lengths, dtype=float))


class _Builder:
    def __init__(self, system, number, starts, nodes, node_of, quat, joints, others, parent, pjoint, order):
        self.system, self.number, self.starts = system, number, starts
        self.nodes, self.node_of, self.quat = nodes, node_of, quat
        self.joints, self.others = joints, others
        self.parent, self.pjoint, self.order = parent, pjoint, order
        self.node_at = {}  # coordinate -> (node, local index)
        for i, (part, start) in enumerate(nodes):
            for c in range(len(part.coordinates)):
                self.node_at[start + c] = (i, c)
        self.x_coord = [c for c in range(system.n) if c not in self.node_at]
        self.x_index = {c: i for i, c in enumerate(self.x_coord)}

    def layout(self):
        nodes, joints = self.nodes, self.joints
        rigid = [_node(part) == RIGID_NODE for part, _ in nodes]
        v = [6 if r else 3 for r in rigid]
        k = [joints[j][0].size if j >= 0 else 0 for j in self.pjoint]
        d = [a + b for a, b in zip(v, k)]
        yoff = np.cumsum([0] + d)
        rows = np.cumsum([0] + k)
        end = [self._end_of(i, j) for i, j in enumerate(self.pjoint)]
        loops = [j for j in range(len(joints)) if j not in set(self.pjoint)]
        xrow_row, segs, joint_xrow, joint_xseg = [], [], [-1] * len(joints), [[-1, -1] for _ in joints]
        for j in loops:
            con, row = joints[j]
            ends = [self.node_of[p.name] for p in con.parts if p is not None]
            joint_xrow[j] = len(xrow_row)
            place = 0
            for e, part in enumerate(con.parts):
                if part is not None:
                    joint_xseg[j][e], place = place, place + 1
            for r in range(con.size):
                xrow_row.append(row + r)
                segs.append(ends)
        exprs, gen, phi_outputs, phi_rates, own = self._generated(xrow_row, segs)
        seg_ptr = np.cumsum([0] + [len(s) for s in segs])
        patterns = _patterns(gen, len(xrow_row), len(self.x_coord))
        band = dict(band_pos=_ints([]), band_width=_ints([]))
        if not nodes and len(xrow_row) + len(self.x_coord) > DENSE_SCHUR_MAX and _diagonal(gen, len(self.x_coord)):
            position, width = band_order(patterns["xa_ptr"], patterns["xa_col"], len(xrow_row))
            band = dict(band_pos=position, band_width=_ints([width]))
        kernel = [self._joint(con) for con, _ in joints]
        numbers = _numbers([part for part, _ in nodes], [con for con, _ in joints], self.number)
        sizes = [self.system.n, sum(c.size for c in self.system.constraints), int(yoff[-1]),
                 int(rows[-1])]
        layout = Layout(
            node_kind=_ints([RIGID if r else PARTICLE for r in rigid]), node_q=_ints([s for _, s in nodes]),
            node_v=_ints(v), node_k=_ints(k), node_yoff=_ints(yoff[:-1]),
            node_rows=_ints(rows[:-1]), node_parent=_ints(self.parent), node_joint=_ints(self.pjoint),
            node_end=_ints(end), node_transport=_ints([self._transport(i, j, rigid) for i, j in enumerate(self.pjoint)]),
            order=_ints(self.order),
            joint_kinds=_ints([x[0] for x in kernel], (-1, 2)), joint_start=_ints([x[1] for x in kernel], (-1, 2)),
            joint_node=_ints([[len(self.nodes) if p is None else self.node_of[p.name] for p in con.parts] for con, _ in joints],
                             (-1, 2)),
            joint_program=_ints([x[2] for x in kernel], (-1, MAX_ROWS, 3)),
            joint_k=_ints([con.size for con, _ in joints]), joint_row=_ints([row for _, row in joints]),
            joint_xrow=_ints(joint_xrow), joint_xseg=_ints(joint_xseg, (-1, 2)),
            x_coord=_ints(self.x_coord), xrow_row=_ints(xrow_row), xseg_ptr=_ints(seg_ptr),
            xseg_node=_ints([i for s in segs for i in s]),
            quat_row=_ints([self.quat[f"{part.name}.unit_quaternion"] if r else -1
                            for (part, _), r in zip(nodes, rigid)]),
            sizes=_ints(sizes), **numbers, **gen, **patterns, **band)
        return layout, exprs, phi_outputs, phi_rates, own

    def _end_of(self, i, j):
        if j < 0:
            return 0
        parts = self.joints[j][0].parts
        return 0 if parts[0] is not None and self.node_of[parts[0].name] == i else 1

    def _transport(self, i, j, rigid):
        """How node i's accelerations follow its parent's when its joint is locked (tree.py):
        by the rigid transport between two rigid bodies, with the joint's offset d when
        its rows are world components of d (these are not invariant under rotation). A
        rigid root on such a joint to the world is marked too (tree.py's null space)."""
        p = self.parent[i]
        if j < 0 or not rigid[i] or (p >= 0 and not rigid[p]):
            return GENERAL
        operations = {op for op, *_ in KINDS[self.joints[j][0].joint_kind].program}
        if COMPONENT in operations:
            return RIGID_COMPONENTS
        return GENERAL if p < 0 else RIGID_INVARIANT

    def _joint(self, con):
        kinds, starts = [], []
        for part in con.parts:
            if part is None:
                kinds.append(WORLD)
                starts.append(0)
            else:
                i = self.node_of[part.name]
                kinds.append(RIGID if _node(part) == RIGID_NODE else PARTICLE)
                starts.append(self.nodes[i][1])
        program = np.zeros((MAX_ROWS, 3), dtype=np.int64)
        program[:con.size] = KINDS[con.joint_kind].program
        return kinds, starts, program

    def _generated(self, xrow_row, segs):
        """Expressions of the generated function, where each output goes, and the counts of its
        last outputs: φ of the extra rows (with a φ), and before them their ∂φ/∂t where a row
        reads t in a model of extra coordinates alone (compiled/extra_projection.py; else none)."""
        system, node_at, x_index = self.system, self.node_at, self.x_index
        Q, C = {}, {}
        for element in system.forces:
            for i in element.indices:
                if element.Q[i] != 0:
                    Q[int(i)] = Q.get(int(i), 0) + element.Q[i]
        for con in system.constraints:
            for i in con.indices:
                if con.C[i] != 0:
                    C[int(i)] = C.get(int(i), 0) + con.C[i]
        M, own_q, own = [], [], []  # own: (part, its first coordinate, its first M entry, its first Q output)
        for part, start in zip(system.parts, self.starts):
            if int(start) in node_at:
                continue
            count = len(part.coordinates)
            if part.kernel_arrays is not None:
                own.append((part, int(start), len(M), len(own_q)))
                own_q += range(int(start), int(start) + count)
                M += [(x_index[int(start) + a], x_index[int(start) + b], None)
                      for a in range(count) for b in range(count)]
                continue
            for a in range(len(part.coordinates)):
                if part.Q[a] != 0:
                    Q[int(start) + a] = Q.get(int(start) + a, 0) + part.Q[a]
                for b in range(len(part.coordinates)):
                    if part.M[a, b] != 0:
                        M.append((x_index[int(start) + a], x_index[int(start) + b], part.M[a, b]))
        rows, b, phi, rates, placed = [], [], [], [], sum(len(s) for s in segs)
        at_rest = {s: 0 for s in system.qd_symbols}  # φ̇ = A q̇ + ∂φ/∂t: ∂φ/∂t is φ̇ at q̇ = 0
        for con, row in self.others:
            for r in range(con.size):
                if con.b[r] == 0 and all(con.a[r, int(i)] == 0 for i in con.indices):
                    continue  # a row that vanishes identically (a planar body's out-of-plane rows): no extra row
                xr = len(xrow_row)
                xrow_row.append(row + r)
                touched = sorted({node_at[int(i)][0] for i in con.indices if int(i) in node_at
                                  and con.a[r, int(i)] != 0})
                segs.append(touched)
                first, placed = placed, placed + len(touched)
                for i in con.indices:
                    entry = con.a[r, int(i)]
                    if entry == 0:
                        continue
                    if int(i) in node_at:
                        node, local = node_at[int(i)]
                        rows.append((xr, 7 * (first + touched.index(node)) + local, -1, entry))
                    else:
                        rows.append((xr, -1, x_index[int(i)], entry))
                if con.b[r] != 0:
                    b.append((xr, con.b[r]))
                if con.phi is not None and con.phi[r] != 0 and con.phi[r] is not sp.nan:
                    phi.append(con.phi[r])
                    rates.append(sp.S.Zero if con.psi is None else sp.sympify(con.psi[r]).xreplace(at_rest))
        inputs = [g for part, *_ in own for g in part.kernel_arrays.gravity]
        # ∂φ/∂t only where a row's φ reads t, for the projection of a model of extra coordinates alone
        rates = rates if not node_at and any(r != 0 for r in rates) else []
        exprs = (list(Q.values()) + [None] * len(own_q) + list(C.values()) + [e for *_, e in M]
                 + [e for *_, e in rows] + [e for _, e in b] + inputs + rates + phi)
        m_start = len(Q) + len(own_q) + len(C)
        g_start = m_start + len(M) + len(rows) + len(b)
        own = [Own(start, m_start + m0, len(Q) + q0, g_start + 3 * k, tuple(part.kernel_arrays[:6]))
               for k, (part, start, m0, q0) in enumerate(own)]
        gen = dict(gen_q=_ints(list(Q) + own_q), gen_c=_ints(list(C)), gen_mi=_ints([x[0] for x in M]),
                   gen_mj=_ints([x[1] for x in M]), gen_arow=_ints([x[0] for x in rows]),
                   gen_aseg=_ints([x[1] for x in rows]), gen_acol=_ints([x[2] for x in rows]),
                   gen_brow=_ints([x[0] for x in b]))
        return exprs, gen, len(phi), len(rates), own
