"""The run loop's recording stage: one row per output time — the state, its kinetic and
total energy, the power of its forces that derive from no potential (Data.power), its
largest constraint residuals and the model's declared outputs — kept for
the Trajectory and, when a file is asked for, written as the run goes
(trajectory.TrajectoryWriter)."""

import os

import numpy as np

from ..core.errors import ModelError
from ..model.outputs import OutputEvaluator
from .trajectory import Trajectory, TrajectoryWriter

MEMORY_SHARE = 0.8  # of the memory available when a run starts: the most its rows may take


class Recorder:
    """The ``rows`` rows of a run on ``data`` (a run's Data), held in arrays made at the
    start (the memory they take is known then: ``row_bytes``), written to ``out`` (.npz or
    .csv) too when given, from ``open`` on."""

    def __init__(self, data, rows, out=None):
        self.data, self.out = data, out
        self.run = run_of(data)
        self.powered = bool(data.model.working_forces(data.parameter_values))  # else every row's power is 0
        self.outputs = OutputEvaluator(data)
        n, m = len(data.model.coordinates), len(self.outputs.names)
        _check_fits(rows, row_bytes(n, m), out)
        self.count = 0
        self.columns = dict(t=np.empty(rows), q=np.empty((rows, n)), qd=np.empty((rows, n)), energy=np.empty(rows),
                            power=np.empty(rows), kinetic=np.empty(rows), residual_position=np.empty(rows),
                            residual_velocity=np.empty(rows), outputs=np.empty((rows, m)))
        self.writer = None
        self.events = []  # trajectory.Event, appended by a run with unilateral constraints (impacts.py)
        self.contact_forces = None  # the run's {gap name: (λ, friction)} of (t, q, q̇, held gaps) (impacts.py)
        self.counted = 0  # the events up to the last row (contact outputs)
        self.held = set()  # the gaps held at the last row, by its events

    def open(self):
        """Start the file, if one was asked for (a path that cannot be written fails here)."""
        if self.out is not None:
            self.writer = TrajectoryWriter(self.out, self.data.model.coordinates, self.outputs.names, rows=self.trajectory,
                                           run=self.run)

    @property
    def t(self):
        """The times recorded so far."""
        return self.columns["t"][:self.count]

    def record(self, t, q, qd, projection=None, compiled_energy=False, arrays=None, projected=None):
        """A row at (t, q, q̇). Its residuals and energies are the compiled ones where the
        kernel covers the model: ``projected`` (projection.Projected: the state's row came
        from a projection, which measured them) or else ``projection``'s rows
        (compiled/rows.py), the energies only when ``compiled_energy``; otherwise they are
        evaluated here, from ``arrays`` (the ConstraintArrays at the state) where at hand."""
        data = self.data
        if projected is None:
            if projection is not None:
                phi, psi, kinetic, potential = projection.residuals_energy(t, q, qd)
            else:
                phi, psi = data.constraint_residuals(t, q, qd) if arrays is None else (arrays.phi, arrays.psi)
            residuals = _max_abs(phi), _max_abs(psi)
        else:
            kinetic, potential, *residuals = projected[2:]
        if not compiled_energy:
            kinetic, potential = data.energy(t, q, qd)
        self._store([t], q[None, :], qd[None, :], kinetic, potential, *residuals)

    def record_rows(self, times, rows, compiled_energy):
        """A row at each of ``times`` from their projected states ``rows``
        (projection.ProjectedRows, with their residuals and, where ``compiled_energy``,
        energies; else the energies are evaluated here), as ``record`` would one by one."""
        kinetic, potential, residual_position, residual_velocity = rows.found[:, :4].T
        if not compiled_energy:
            kinetic, potential = np.array([self.data.energy(t, q, qd) for t, q, qd in zip(times, rows.q, rows.qd)]).T
        self._store(times, rows.q, rows.qd, kinetic, potential, residual_position, residual_velocity)

    def _store(self, times, q, qd, kinetic, potential, residual_position, residual_velocity):
        """Rows at ``times`` (q, q̇ a row each; the others an entry each, or one value for a
        single row) into the columns, with the model's declared outputs, and to the file."""
        rows_at = slice(self.count, self.count + len(times))
        c = self.columns
        c["t"][rows_at], c["q"][rows_at], c["qd"][rows_at] = times, q, qd
        c["kinetic"][rows_at], c["energy"][rows_at] = kinetic, kinetic + potential
        c["power"][rows_at] = self.data.powers(times, q, qd) if self.powered else 0.0
        c["residual_position"][rows_at], c["residual_velocity"][rows_at] = residual_position, residual_velocity
        if self.outputs:
            for i, (t, q_row, qd_row) in enumerate(zip(times, q, qd)):
                c["outputs"][self.count + i] = self.outputs.evaluate(t, q_row, qd_row,
                                                                     contacts=self._contacts(t, q_row, qd_row))
        self.count += len(times)
        if self.writer is not None:
            self.writer.append(self.trajectory("running", rows=rows_at))

    def _contacts(self, t, q, qd):
        """{gap name: (force, impulse, friction)} at a row at t, from the run's events up to t (rows
        come in time order, the run's events ahead of them): the forces of the gaps held
        there (a "contact" event holds a gap, a "release" opens it), and the normal impulses
        ("impact", "contact") since the previous row; None without unilateral gaps."""
        if self.contact_forces is None:
            return None
        impulses = {}
        while self.counted < len(self.events) and self.events[self.counted].t <= t:
            event = self.events[self.counted]
            if event.kind == "contact":
                self.held.add(event.name)
            elif event.kind == "release":
                self.held.discard(event.name)
            if event.kind in ("impact", "contact"):
                impulses[event.name] = impulses.get(event.name, 0.0) + event.impulse
            self.counted += 1
        forces = self.contact_forces(t, q, qd, self.held)
        found = {}
        for name in set(forces) | set(impulses):
            force, friction = forces.get(name, (0.0, np.zeros(3)))
            found[name] = (force, impulses.get(name, 0.0), friction)
        return found

    def close(self, status):
        """Finish the file, if any, with the run's ``status``."""
        if self.writer is not None:
            self.writer.status = status
            self.writer.close()

    def trajectory(self, status, rows=None):
        """The rows so far (``rows``: a slice of them) as a Trajectory with ``status``; its
        arrays are views of the recorder's."""
        rows = slice(0, self.count) if rows is None else rows
        c = {name: column[rows] for name, column in self.columns.items()}
        return Trajectory(tuple(self.data.model.coordinates), c["t"], c["q"], c["qd"], c["energy"], c["kinetic"],
                          c["residual_position"], c["residual_velocity"], status, outputs=c["outputs"],
                          output_names=tuple(self.outputs.names), power=c["power"], events=tuple(self.events),
                          **self.run)


def run_of(data):
    """The model a run on ``data`` runs (Trajectory's ``model``, ``model_file``,
    ``parameters``): its name, its file, and the values of its parameters not defined by
    others as the run starts (those defined by them follow from these)."""
    system = data.system
    defined = system.definitions or {}
    return {"model": system.name, "model_file": system.source_file,
            "parameters": {name: value for name, value in data.parameters.items() if name not in defined}}


def row_bytes(n, m):
    """The bytes of one row of a run with n coordinates and m outputs (its output time
    included)."""
    return 8 * (2 * n + m + 7)


def _check_fits(rows, size, out):
    """Raise ModelError when ``rows`` rows of ``size`` bytes would take more than
    MEMORY_SHARE of the memory available now: refused before the run starts, not lost to
    a MemoryError in the middle of it."""
    available = available_memory()
    need = rows * size
    if available is not None and need > MEMORY_SHARE * available:
        raise ModelError(f"{rows:,} output rows would take {_bytes(need)}, more than this machine has free "
                         f"({_bytes(available)}): ask for fewer rows (a larger dt or a shorter run)"
                         + (f"; nothing was written to {out}" if out is not None else ""))


def available_memory():
    """The bytes of memory available to a new allocation (MemAvailable of /proc/meminfo;
    the free physical pages elsewhere), or None where neither is known."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def _bytes(count):
    """``count`` bytes in words: 7.3 GB, 512 MB, ..."""
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if count >= size:
            return f"{count / size:.3g} {unit}"
    return f"{count} bytes"


def _max_abs(values):
    """The largest finite |value| (0 where none is finite): NaN marks rows without that level."""
    largest = np.abs(values).max(initial=0.0)
    if np.isfinite(largest):
        return float(largest)
    finite = values[np.isfinite(values)]
    return float(np.abs(finite).max()) if finite.size else 0.0

