"""The compiled path: a Template per model structure, an Engine per parameter values.

``Template.build(system)`` lays the System out (layout.build) and compiles its generated
function (codegen.py), or returns None where layout.build does. Systems that
differ only in parameter values (``System.with_parameters``, a Data's ``set_parameters``)
share one Template: the parameters are arguments of the generated function, and the
Layout's numbers (masses, inertias, frame offsets) are re-evaluated per parameter values
(layout.with_parameters), which costs no compilation, and only where a parameter they
depend on changed (a controller's torques do not: ``Template.number_parameters``; those
Engines share one set of buffers, ``Engine.at``). ``Template.engine(p)`` makes the Engine
at parameter values p: its numbers and work buffers. An Engine holds no reference to a System.

``Engine.motion`` returns a ``Motion`` equal to (2.14)'s, or None when the kernel's checks
send the problem to the exact treatment (kernel.py's status); ``motion_copied`` (Data.motion's,
where no shift or drift rule applies) the same in one compiled call (single.py) that copies
the state, evaluates the generated function and the kernel, and writes q̈ and Qc into a new
block beside the copies, which the Motion holds; ``stages`` gives the same
evaluation for an integrator's stages and steps, without the Motion (staged.py);
``motion_batch`` evaluates many states in parallel. Each is one call into the kernel, which
leaves q̈ and Qc in the Engine's own buffers (its Work); a Motion holds copies of them, so
that the next call leaves it as it is.

The kernel's residual check (kernel.CHECKED) runs per call where it can fail: loops, extra
coordinates, particles. On a rigid tree (``Template.mode``) the kernel eliminates by the
articulated-body recursion, a Cholesky factorization of each joint's S^T H^A S (positive
definite, its pivots checked) with bases from closed forms or fully pivoted Gauss–Jordan,
which is backward stable: the relative residual of the equilibrated equations is a small
multiple of the rounding unit at every state the pivot checks accept. There the check is
decided once, at layout time, and a Motion's ``residual`` is computed when first read.
"""

import copy
import functools
import threading

import numpy as np

from ..core.equations import Motion
from . import ahead, codegen, flexible, kernel, layout, staged
from .assembly import Work, make_work
from .projection import Projection
from .extra_projection import ExtraProjection
from .rows import Rows, relative_drift
from .packing import pack, views
from .single import ACCELERATION, FORCE, RATE, STATE, WRONG_SIZE, single
from .threads import THREADS, pool

EMPTY = np.zeros(0)
NO_BODIES = np.zeros(0, dtype=np.int64)  # ``stages``' ``starts`` of a state in (q, q̇) itself
CHUNK = 16  # fewest rows a thread takes at a time
FLOAT = np.dtype(float)


def _plain(q, qd):
    """Whether q and q̇ are writeable C-contiguous 1-d float64 arrays (the type single.motion_into
    is compiled for: numba would compile it anew for another)."""
    return type(q) is np.ndarray and q.dtype is FLOAT and q.ndim == 1 and q.strides[0] == 8 and q.flags.writeable \
        and type(qd) is np.ndarray and qd.dtype is FLOAT and qd.ndim == 1 and qd.strides[0] == 8 \
        and qd.flags.writeable


class Template:
    """What the Systems with one structure share: the Layout (with the numbers of the System
    it was built from, at parameter values ``p``) and the compiled generated function."""

    def __init__(self, system, L, exprs, phi_outputs, phi_rates, own):
        self.L, self.n, self.p = L, system.n, system.parameter_values
        self.phi_outputs = phi_outputs  # the generated function's last outputs: φ of the extra rows
        self.phi_rates = phi_rates  # 0, or phi_outputs: ∂φ/∂t of those rows just before them (layout._generated)
        self.names = tuple(system.parameters)
        self.sources = layout.sources(L, system)  # the parts and joints its numbers are read from
        self.outputs = len(exprs)
        generated = codegen.compile_expressions(exprs, system.q_symbols, system.qd_symbols,
                                                system.parameter_symbols) if any(e is not None for e in exprs) else None
        # the flexible parts' M and Q written after the generated function (layout.Own, flexible.py)
        self.module = flexible.Filled(generated, own) if own else generated
        self.closes_loops = L.xrow_row.size > 0  # extra rows: loop joints or other constraints
        self.general = kernel.RIGID_TREE if layout.rigid_tree(L) else kernel.GENERAL  # kernel.motion's last argument
        # the kernel's mode per call: the residual checked where it can fail (module docstring)
        self.mode = kernel.UNCHECKED if self.general is kernel.RIGID_TREE else kernel.CHECKED
        used = layout.number_parameters(L, self.sources, system.parameters)
        # the parameters the Layout's numbers use: values that differ only in others share L as it is
        self.number_parameters = np.array([self.names.index(n) for n in sorted(used)], dtype=np.int64)
        self.on_layout = None  # the first Engine on L itself, whose buffers the later ones share
        self.lock = threading.Lock()

    @classmethod
    def build(cls, system):
        found = layout.build(system)
        return None if found is None else cls(system, *found)

    def engine(self, p):
        """The Engine at parameter values ``p`` (an array in the model's parameter order): this
        Template's structure and code, its own numbers where they differ from the Layout's
        (masses, inertias, frames), else the buffers of the first Engine on the Layout (a
        controller's torques: ``Engine.at``)."""
        p = np.array(p, dtype=float)
        if not np.array_equal(p[self.number_parameters], self.p[self.number_parameters]):
            return Engine(self, layout.with_parameters(self.L, self.sources, dict(zip(self.names, p))), p)
        with self.lock:
            if self.on_layout is None:
                self.on_layout = Engine(self, self.L, p)
                return self.on_layout
        return self.on_layout.at(p)


class Engine:
    """The compiled path for one System at its parameter values ``p`` (Layout ``L``)."""

    def __init__(self, template, L, p):
        self.template, self.L, self.p = template, L, p
        self.n, self.outputs, self.module = template.n, template.outputs, template.module
        self.closes_loops, self.general, self.mode = template.closes_loops, template.general, template.mode
        self.gen = np.zeros(self.outputs)
        self.packed = pack(L)
        self.work, self.W = self.new_work()
        self.buffers = (*self.packed, *self.work)  # kernel.motion's last six arguments
        self.no_freedom = np.zeros((self.n, 0))  # the nullspace of a unique motion (read-only)
        self.no_freedom.flags.writeable = False
        self.lock = threading.Lock()
        self.batch_lock = threading.Lock()
        self.batch_works = []  # one packed Work per thread of motion_batch, made on first use
        self.projections = []  # the Projection, once made (``at``'s copies get it on their parameter values)
        self.origin = self  # the Engine whose buffers this one shares (``at``'s copies: the one they were made of)
        self.staged = {}  # the compiled stages (staged.Stages) per integrator form, once made
        self.single = None  # ``motion_into``'s compiled call (single.single), once made
        # φ of the kernel's rows, for the relative drift of a state off the manifold of a model with extra rows
        self.rows = Rows(L, self.packed, int(L.sizes[1])) if self.closes_loops else None
        self.generated_phi = slice(self.outputs - template.phi_outputs, self.outputs)  # φ of the extra rows in gen

    def at(self, p):
        """This Engine at other parameter values that its Layout's numbers do not use (a
        controller's torques): the same buffers and locks, so a System per control sample
        allocates nothing."""
        other = copy.copy(self)
        other.p = p
        other.staged, other.single = {}, None
        other.projections = [made and made.at(other) for made in self.projections]
        return other

    def at_rest(self):
        """This Engine with no gravity, for calls at q̇ = 0 with no generated forces (compiled/projection.py)."""
        return Engine(self.template, self.L._replace(node_mg=np.zeros_like(self.L.node_mg)), self.p)

    def projection(self):
        """The kernel's projection on this Engine's Layout (compiled/projection.py; extra_projection.py
        for a model of extra coordinates alone), or None where neither covers the System. A copy
        (``at``) takes its origin's, made there once for all its copies (a Data per run would
        otherwise make its own: a tenth of a millisecond per body)."""
        if not self.projections:
            if self.origin is self:
                self.projections.append(Projection.build(self) or ExtraProjection.build(self))
            else:
                made = self.origin.projection()
                self.projections.append(made and made.at(self))
        return self.projections[0]

    def stages(self, starts=NO_BODIES):
        """The compiled stages of an integrator on this Engine (staged.Stages) for states in its
        form with rigid bodies' quaternions at ``starts`` (velocity_form.py; none: (q, q̇))."""
        key = starts.tobytes()
        if key not in self.staged:
            self.staged[key] = staged.Stages(self, starts)
        return self.staged[key]

    def new_work(self):
        """(packed buffers, Work of views into them)."""
        work = make_work(self.L)
        packed = pack(work)
        return packed, views(Work, work, *packed)

    def warm(self, q, qd):
        """Compile (or load from the cache) everything ``motion`` calls, at the state (q, q̇):
        the generated function first, then, once the helpers this process started (ahead.py)
        have put their parts of the kernel into the cache, the kernel, and ``motion_copied``'s call."""
        if self.module is not None:
            self.module.evaluate(0.0, q, qd, self.p, self.gen)
        ahead.finish()
        self.motion(0.0, q, qd)
        self.motion_copied(0.0, np.array(q, dtype=float), np.array(qd, dtype=float))

    def motion(self, t, q, qd, bshift=None, drift=False, kept=None):
        """A Motion at (t, q, q̇) (validated 1-d float arrays), or None for the exact path.
        bshift: added to b per row of the System (Baumgarte's −2αφ̇ − β²φ); ``drift``: the
        state may lie off the constraint manifold (an integrator's stage: the drift rule,
        kernel.motion). Its q̈ and Qc are new arrays; its residual is computed when first
        read where the kernel's mode does not check it per call (module docstring), at
        ``kept``: copies of (q, q̇) its caller holds (Data.motion's, shared with λ), else
        made here."""
        bshift = EMPTY if bshift is None else bshift
        with self.lock:
            status, residual = self._solved(t, q, qd, bshift, drift, self.mode)
            if status != kernel.OK:
                return None
            qdd, Qc = self.W.qdd.copy(), self.W.Qc.copy()
        if self.mode != kernel.CHECKED:  # the state as it is now, for the residual when read
            q, qd = (q.copy(), qd.copy()) if kept is None else kept
            residual = functools.partial(self.checked_residual, t, q, qd, bshift.copy() if bshift.size else EMPTY,
                                         drift)
        return Motion.made(qdd, True, self.no_freedom, Qc, residual, "tree (Baraff)")

    def motion_copied(self, t, q, qd, drift=False):
        """``motion(t, q, q̇, drift=drift)`` for a model whose kernel needs no drift (no extra
        rows) or a state on the manifold, in one compiled call that copies the state too
        (single.py): (the Motion, or None where the kernel declines; the copies of q and q̇).
        None where q or q̇ is not a writeable 1-d float64 array of n contiguous entries (the
        caller's checks then say what it is)."""
        block = np.empty((4, self.n))
        found = self.motion_into(t, q, qd, block)
        if found is None:
            return None
        q, qd = block[STATE], block[RATE]
        ok, residual = found
        if not ok:
            return None, q, qd
        if self.mode != kernel.CHECKED:
            residual = functools.partial(self.checked_residual, t, q, qd, EMPTY, drift)
        return Motion.made(block[ACCELERATION], True, self.no_freedom, block[FORCE], residual, "tree (Baraff)"), q, qd

    def motion_into(self, t, q, qd, block):
        """single.motion_into at (t, q, q̇), its rows (copies of q, q̇; q̈, Qc) into ``block``
        (4 × n): (whether the kernel took the state — else q̈ and Qc are not written —, its
        residual where it checks it per call, else 0), or None where q or q̇ is not a writeable
        1-d float64 array of n contiguous entries (nothing written; the caller's checks then say
        what it is)."""
        if not _plain(q, qd):
            return None
        with self.lock:
            if self.single is None:
                self.single = single(self)
            status, residual = self.single(float(t), q, qd, block)
        return None if status == WRONG_SIZE else (status == kernel.OK, residual)

    def checked_residual(self, t, q, qd, bshift, drift):
        """The kernel's relative residual (kernel.motion, CHECKED) of the motion at (t, q, q̇)."""
        with self.lock:
            return self._solved(t, q, qd, bshift, drift, kernel.CHECKED)[1]

    def _solved(self, t, q, qd, bshift, drift, mode):
        """kernel.motion's (status, residual) at (t, q, q̇) in ``mode``, its q̈ and Qc left
        in this Engine's Work (the caller holds the lock): the generated function's outputs
        into ``gen``, then the kernel's one entry (kernel.motion_rates, no rates) with its
        ``drift``: the state's relative drift where ``drift`` and the model closes loops, else −1."""
        if self.module is not None:
            self.module.evaluate(float(t), q, qd, self.p, self.gen)
        delta = self.relative_drift(q, qd) if drift and self.closes_loops else -1.0
        return kernel.motion_rates(q, qd, self.gen, bshift, *self.buffers, mode, delta, self.general, NO_BODIES, EMPTY)

    def relative_drift(self, q, qd):
        """The state's relative drift (rows.relative_drift), the extra rows' φ read from ``gen``
        as the generated function left it at this state."""
        return relative_drift(self.rows.largest_phi(q, qd), self.gen, self.generated_phi.start,
                              self.generated_phi.stop, q)

    def motion_batch(self, t, q, qd):
        """(q̈ per row, status per row) for states q, q̇ (B × n) at times t (B,): one thread
        per core, each with its own Work, taking chunks of rows in turn (a thread slowed by
        other load does fewer), the kernels running without the GIL."""
        count = q.shape[0]
        qdd, status = np.zeros((count, self.n)), np.zeros(count, dtype=np.int64)
        size = max(CHUNK, -(-count // (THREADS * 8)))
        chunks = iter(range(0, count, size))  # next() on it is atomic under the GIL

        def worker(work):
            gen = np.zeros((size, self.outputs))  # the generated outputs of one chunk, reused chunk after chunk
            for a in chunks:
                b = min(a + size, count)
                if self.module is not None:
                    self.module.evaluate_rows(t[a:b], q[a:b], qd[a:b], self.p, gen[:b - a])
                kernel.motion_rows(q[a:b], qd[a:b], gen[:b - a], *self.packed, *work, self.general, self.mode, qdd[a:b],
                                   status[a:b])

        threads = max(1, min(THREADS, -(-count // size)))
        with self.batch_lock:
            while len(self.batch_works) < threads:
                self.batch_works.append(self.new_work()[0])
            if threads > 1:
                list(pool().map(worker, self.batch_works[:threads]))
            else:
                worker(self.batch_works[0])
        return qdd, status

