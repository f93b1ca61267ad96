"""The run loop's recording stage: one row per output time — the state, its kinetic and
total energy, its largest constraint residuals and the model's declared outputs — kept for
the Trajectory and, when a file is asked for, written as the run goes
(trajectory.TrajectoryWriter)."""

import numpy as np

from ..model.outputs import OutputEvaluator
from .trajectory import Trajectory, TrajectoryWriter

COLUMNS = ("t", "q", "qd", "energy", "kinetic", "residual_position", "residual_velocity", "outputs")
_NO_OUTPUTS = np.zeros(0)  # a row's outputs where the model declares none (read-only)
_NO_OUTPUTS.flags.writeable = False


class Recorder:
    """The rows of a run on ``data`` (a run's Data), written to ``out`` (.npz or .csv) too
    when given."""

    def __init__(self, data, out=None):
        self.data = data
        self.outputs = OutputEvaluator(data)
        self.rows = {k: [] for k in COLUMNS}
        self.columns = tuple(self.rows.values())  # in COLUMNS' order (``record``)
        self.writer = None if out is None else TrajectoryWriter(out, data.coordinates, self.outputs.names)

    @property
    def t(self):
        """The times recorded so far."""
        return self.rows["t"]

    def record(self, t, q, qd, correction=None, compiled_energy=False, arrays=None, corrected=None):
        """A row at (t, q, q̇). Its residuals and energies are the compiled ones where the
        kernel covers the model: ``corrected`` (correction.Corrected: the state's row came
        from a correction, which measured them) or else ``correction``'s rows
        (compiled/rows.py), the energies only when ``compiled_energy``; otherwise they are
        evaluated here, from ``arrays`` (the ConstraintArrays at the state) where at hand."""
        data = self.data
        if corrected is None:
            if correction is not None:
                phi, psi, kinetic, potential = correction.residuals_energy(q, qd)
            else:
                phi, psi = data.constraint_residuals(t, q, qd) if arrays is None else (arrays.phi, arrays.psi)
            residuals = _max_abs(phi), _max_abs(psi)
        else:
            kinetic, potential, *residuals = corrected[2:]
        if not compiled_energy:
            kinetic, potential = data.energy(t, q, qd)
        values = (t, np.array(q), np.array(qd), kinetic + potential, kinetic, *residuals,
                  self.outputs.evaluate(t, q, qd) if self.outputs else _NO_OUTPUTS)
        for column, value in zip(self.columns, values):
            column.append(value)
        if self.writer is not None:
            self.writer.append(_chunk(data.coordinates, dict(zip(COLUMNS, values)), self.outputs.names))

    def close(self, status):
        """Finish the file, if any, with the run's ``status``."""
        if self.writer is not None:
            self.writer.status = status
            self.writer.close()

    def trajectory(self, status):
        """The rows so far as a Trajectory with ``status``."""
        r, n = self.rows, len(self.data.coordinates)
        return Trajectory(tuple(self.data.coordinates), np.array(r["t"]), np.array(r["q"]).reshape(-1, n),
                          np.array(r["qd"]).reshape(-1, n), np.array(r["energy"]), np.array(r["kinetic"]),
                          np.array(r["residual_position"]), np.array(r["residual_velocity"]), status,
                          outputs=np.array(r["outputs"], dtype=float).reshape(len(r["t"]), len(self.outputs.names)),
                          output_names=tuple(self.outputs.names))


def _max_abs(values):
    """The largest finite |value| (0 where none is finite): NaN marks rows without that level."""
    largest = np.abs(values).max(initial=0.0)
    if np.isfinite(largest):
        return float(largest)
    finite = values[np.isfinite(values)]
    return float(np.abs(finite).max()) if finite.size else 0.0


def _chunk(coordinates, row, output_names):
    return Trajectory(tuple(coordinates), np.array([row["t"]]), row["q"][None, :], row["qd"][None, :],
                      np.array([row["energy"]]), np.array([row["kinetic"]]), np.array([row["residual_position"]]),
                      np.array([row["residual_velocity"]]), outputs=row["outputs"][None, :],
                      output_names=tuple(output_names))
