"""Trajectories and their files.

A ``Trajectory`` holds one row per output time: ``t``, ``q``, ``qd``, the largest
position and velocity constraint residuals, the total energy, the power of the forces that
derive from no potential (``Data.power``: dampers, actuation, friction), and the model's
declared ``outputs`` (one column per name in ``output_names``: mbsynth.model.outputs). Files:

- ``.npz``: arrays ``t``, ``q``, ``qd``, ``coordinates`` (plus ``energy``, ``power``,
  ``residual_position``, ``residual_velocity``, ``status``, ``outputs``, ``output_names``,
  and the run's model: ``model`` (its name), ``model_file``, ``parameter_names``,
  ``parameter_values``: the values of its parameters not defined by others, at the start);
  and the run's events (impacts, contacts that close or open: analysis/impacts.py) as
  ``event_t``, ``event_name``, ``event_kind``, ``event_impulse``;
- ``.csv``: a header ``t, <coordinate>..., <coordinate>_dot..., energy, <output>...`` and
  one row per time.

A file's format is its suffix in any case (``run.NPZ`` is an .npz file: core.files.file_format).

``TrajectoryWriter`` writes while a run goes on, so an interrupted or failed run keeps
everything computed so far, and never leaves half a file under the final name: CSV
rows are appended to ``FILE.partial``, cut back to its last complete row when the run
ends and renamed to FILE only when the run completed (a CSV has no place for the
status: an interrupted, failed or killed run leaves its rows in FILE.partial, and no
FILE of an earlier run); NPZ is checkpointed to a temporary file that replaces FILE
atomically (and is removed if writing it fails), with the run's status inside. A path
that cannot be written (core.files.unwritable) is refused before anything is made.
"""

import csv
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..core.errors import ModelError
from ..core.files import file_format, unwritable, write_atomically

FORMATS = (".npz", ".csv")
COMPLETED = "completed"


class Event(NamedTuple):
    """What happened at a unilateral constraint (analysis/impacts.py) at time ``t``: ``kind``
    "impact" (a velocity jump, ``impulse`` its Λ), "contact" (the gap closed and holds: a
    persistent contact, ``impulse`` what brought it to rest), "release" (it opened), or at an
    impact of a contact with friction "stick" or "slip" (``impulse`` the tangential |Λ_t|),
    "slip" and "stick" too where a held one starts to slide or to stick (``impulse`` 0)."""

    t: float
    name: str
    kind: str
    impulse: float


@dataclass
class Trajectory:
    coordinates: tuple
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    energy: np.ndarray
    kinetic: np.ndarray
    residual_position: np.ndarray
    residual_velocity: np.ndarray
    status: str = COMPLETED
    stats: dict = field(default_factory=dict)
    outputs: np.ndarray = None  # T × len(output_names): the model's declared outputs
    output_names: tuple = ()
    power: np.ndarray = None  # per row: the power of the forces that derive from no potential (Data.power)
    model: str = ""  # the name of the model run
    model_file: str = ""  # its file ("" where it was not read from one)
    parameters: dict = field(default_factory=dict)  # its parameters not defined by others, at the start
    events: tuple = ()  # Event: impacts, contacts closing and opening, in time order

    def __post_init__(self):
        if self.outputs is None:
            self.outputs = np.zeros((len(self.t), len(self.output_names)))
        if self.power is None:
            self.power = np.zeros(len(self.t))

    @property
    def work(self):
        """W(t): the work those forces did from the first row on, per row (negative where
        they dissipate): ``power`` integrated over the rows through its cubic spline (an
        error of order dt⁴ in the output interval dt); NaN where the power is not known (a
        CSV file keeps none)."""
        if self.t.size < 2 or not np.any(self.power):
            return np.zeros(self.t.size)
        if not np.all(np.isfinite(self.power)):
            return np.full(self.t.size, np.nan)
        import scipy.interpolate  # loaded only by the runs that ask for their work (start-up)
        return scipy.interpolate.CubicSpline(self.t, self.power).antiderivative()(self.t)

    @property
    def energy_drift(self):
        """max |E(t) − E(0) − W(t)| (the change of T + V beyond the work of the forces that
        derive from no potential, ``work``: the integration's error where nothing else
        changes the energy, ``System.unaccounted_work``) relative to max(|E(0)|, the largest
        kinetic energy): a pendulum whose energy is zero at the start still gets a
        meaningful scale."""
        E = self.energy
        if E.size == 0 or not np.all(np.isfinite(E)):
            return float("nan")
        scale = max(abs(E[0]), float(np.nanmax(np.abs(self.kinetic))) if self.kinetic.size else 0.0)
        return 0.0 if scale == 0 else float(np.abs(E - E[0] - self.work).max() / scale)

    @property
    def max_residual(self):
        values = np.concatenate([self.residual_position, self.residual_velocity])
        values = values[np.isfinite(values)]
        return float(values.max()) if values.size else 0.0

    def column(self, name):
        """The history of one coordinate (``part.coord``), velocity (``part.coord_dot``) or
        output (its column name: ``tip[x]``)."""
        if name in self.output_names:
            return self.outputs[:, self.output_names.index(name)]
        if name in self.coordinates:
            return self.q[:, self.coordinates.index(name)]
        if name.endswith("_dot") and name[:-4] in self.coordinates:
            return self.qd[:, self.coordinates.index(name[:-4])]
        raise KeyError(f"no coordinate or output '{name}'; coordinates: {', '.join(self.coordinates)}"
                       + (f"; outputs: {', '.join(self.output_names)}" if self.output_names else ""))

    def save(self, path):
        """Write the whole trajectory to ``path`` (.npz or .csv), atomically; the CSV of a
        run that did not complete goes to ``path``.partial (see the module docstring)."""
        with TrajectoryWriter(path, self.coordinates, self.output_names, run=run_of(self)) as writer:
            writer.append(self)
            writer.status = self.status


def partial_file(path):
    """FILE.partial: where a CSV run's rows go until the run completes."""
    path = Path(path)
    return path.with_name(path.name + ".partial")


def output_file(path, completed):
    """The file that holds a run's output written to ``path``: ``path`` itself, or for a
    CSV run that did not complete, ``partial_file(path)``."""
    path = Path(path)
    return path if completed or file_format(path) != ".csv" else partial_file(path)


def load_trajectory(path):
    """Read a trajectory written by ``Trajectory.save`` or a run (.npz, .csv or the
    .csv.partial of a run that did not complete)."""
    path = Path(path)
    if file_format(path) == ".npz":
        with np.load(path, allow_pickle=False) as data:
            coordinates = tuple(str(c) for c in data["coordinates"])
            get = {k: data[k] for k in data.files}
        n_rows = get["t"].size
        nan = np.full(n_rows, np.nan)
        names = tuple(str(x) for x in get.get("output_names", ()))
        parameters = dict(zip((str(x) for x in get.get("parameter_names", ())),
                              (float(x) for x in get.get("parameter_values", ()))))
        return Trajectory(coordinates, get["t"], get["q"], get["qd"], get.get("energy", nan),
                          get.get("kinetic", nan), get.get("residual_position", nan), get.get("residual_velocity", nan),
                          str(get.get("status", COMPLETED)), outputs=get.get("outputs"), output_names=names,
                          power=get.get("power", nan), model=str(get.get("model", "")),
                          model_file=str(get.get("model_file", "")), parameters=parameters,
                          events=_events(get))
    if file_format(path) == ".csv" or path.name.lower().endswith(".csv.partial"):
        with path.open(newline="") as f:
            header = next(csv.reader(f))
        if "energy" not in header[1:]:
            raise ModelError(f"{path}: not a trajectory file (its header has no 'energy' column: "
                             "t, coordinates, velocities, energy, outputs)")
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        energy = header.index("energy", 1)  # t, coordinates, velocities, energy, outputs
        n = (energy - 1) // 2
        nan = np.full(data.shape[0], np.nan)
        return Trajectory(tuple(header[1:1 + n]), data[:, 0], data[:, 1:1 + n], data[:, 1 + n:1 + 2 * n],
                          data[:, energy], nan, nan, nan, outputs=data[:, energy + 1:],
                          output_names=tuple(header[energy + 1:]), power=nan)
    raise ModelError(f"{path}: unknown trajectory format (use {' or '.join(FORMATS)})")


def _events(columns):
    """The Events of an .npz file's columns (none where it has no event columns)."""
    if "event_t" not in columns:
        return ()
    return tuple(Event(float(t), str(name), str(kind), float(impulse)) for t, name, kind, impulse in
                 zip(columns["event_t"], columns["event_name"], columns["event_kind"], columns["event_impulse"]))


def run_of(traj):
    """The model of the run ``traj`` records, as ``TrajectoryWriter`` takes it (``run=``)."""
    return {"model": traj.model, "model_file": traj.model_file, "parameters": traj.parameters}


class TrajectoryWriter:
    """Writes trajectory rows as they come (see the module docstring)."""

    def __init__(self, path, coordinates, output_names=(), checkpoint_seconds=2.0, rows=None, run=None):
        """``rows``: where the NPZ checkpoints read every row so far (a callable(status) ->
        Trajectory, a run's recorder) instead of keeping the appended rows themselves.
        ``run``: the model run ({"model", "model_file", "parameters"}: ``run_of``), kept in an NPZ.
        ModelError for a path of another format or where no file can be written."""
        self.path = Path(path)
        self.format = file_format(self.path)
        if self.format not in FORMATS:
            raise ModelError(f"{self.path}: output must end in {' or '.join(FORMATS)}")
        why = unwritable(self.path)
        if why:
            raise ModelError(f"{self.path}: cannot be written there: {why}")
        self.coordinates, self.output_names = tuple(coordinates), tuple(output_names)
        self.run = {"model": "", "model_file": "", "parameters": {}, **(run or {})}
        self.checkpoint_seconds = checkpoint_seconds
        self.status = "running"
        self._rows = rows
        self._chunks = []
        self._last_checkpoint, self._period = time.monotonic(), checkpoint_seconds
        if self.format == ".csv":
            self._partial = partial_file(self.path)
            try:
                self._csv_file = self._partial.open("w", newline="")
            except OSError as err:
                raise OSError(err.errno, f"cannot write {self.path}: {err.strerror or err}") from err
            try:
                self.path.unlink(missing_ok=True)  # an earlier run's file: not this run's output
            except OSError as err:
                self._csv_file.close()
                self._partial.unlink()  # no output of this run: none left behind
                raise OSError(err.errno, f"cannot write {self.path}: {err.strerror or err}") from err
            self._csv = csv.writer(self._csv_file)
            self._csv.writerow(["t", *self.coordinates, *(c + "_dot" for c in self.coordinates), "energy",
                                *self.output_names])
            self._csv_file.flush()
            self._complete = self._csv_file.tell()  # bytes of complete rows
        else:
            self._write_npz()  # an empty file at once: a path that cannot be written fails before the run

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def append(self, traj):
        """Add the rows of a Trajectory (or a chunk of one)."""
        if self.format == ".csv":
            for row in zip(traj.t, traj.q, traj.qd, traj.energy, traj.outputs):
                self._csv.writerow([repr(float(row[0])), *map(repr, map(float, row[1])),
                                    *map(repr, map(float, row[2])), repr(float(row[3])), *map(repr, map(float, row[4]))])
            self._csv_file.flush()
            self._complete = self._csv_file.tell()
        else:
            if self._rows is None:
                self._chunks.append(traj)
            if time.monotonic() - self._last_checkpoint > self._period:
                self._write_npz()

    def close(self):
        """Finish the file: under its final name if the run completed (NPZ: whatever the
        state of the run, which it records)."""
        if self.format == ".csv":
            self._csv_file.close()
            os.truncate(self._partial, self._complete)  # drop a row cut short by a failed write
            if self.status == COMPLETED:
                os.replace(self._partial, self.path)
        else:
            self._write_npz()

    def _write_npz(self):
        """The file with every row so far; the next checkpoint ``checkpoint_seconds`` later,
        or ten times as long as this one took to write (a long run's file grows: its
        checkpoints take at most a tenth of the run); ``checkpoint_seconds=0``: at every
        append."""
        started = time.monotonic()
        chunks = self._chunks if self._rows is None else [self._rows(self.status)]
        n = len(self.coordinates)

        def stack(name, width=None):
            parts = [getattr(c, name) for c in chunks]
            if not parts:
                return np.zeros(0) if width is None else np.zeros((0, width))
            return parts[0] if len(parts) == 1 else np.concatenate(parts)  # one: the rows themselves, no copy

        columns = dict(t=stack("t"), q=stack("q", n), qd=stack("qd", n), coordinates=np.array(self.coordinates),
                       energy=stack("energy"), power=stack("power"), kinetic=stack("kinetic"),
                       residual_position=stack("residual_position"),
                       residual_velocity=stack("residual_velocity"), status=np.array(self.status),
                       outputs=stack("outputs", len(self.output_names)),
                       output_names=np.array(self.output_names, dtype=str), model=np.array(self.run["model"]),
                       model_file=np.array(self.run["model_file"]),
                       parameter_names=np.array(list(self.run["parameters"]), dtype=str),
                       parameter_values=np.array(list(self.run["parameters"].values()), dtype=float))
        events = chunks[-1].events if chunks else ()
        columns.update(event_t=np.array([e.t for e in events], dtype=float),
                       event_name=np.array([e.name for e in events], dtype=str),
                       event_kind=np.array([e.kind for e in events], dtype=str),
                       event_impulse=np.array([e.impulse for e in events], dtype=float))
        try:
            write_atomically(self.path, lambda temporary: np.savez(temporary, **columns))
        except OSError as err:
            raise OSError(err.errno, f"cannot write {self.path}: {err.strerror or err}") from err
        finally:
            self._last_checkpoint = time.monotonic()
            self._period = self.checkpoint_seconds and max(self.checkpoint_seconds,
                                                           10 * (self._last_checkpoint - started))
