"""The singular positions of the parts that turn by angles (euler_body.py), named by part.

At its singular position (the middle angle at ±π/2 for Tait–Bryan, at 0 or π for proper
Euler) a body's angular-velocity map H(α) loses rank: the first and last turns act about one
axis, a direction of angle rates turns nothing and M = blockdiag(m I, HᵀJH) loses rank along
it. That direction is then indeterminate in [M; A] (Result 3) because of the coordinates,
not because a force balance is missing; and near the position the angle rates of a finite
angular velocity grow like 1/|det H|, so that a run crawls. ``AngleParts`` finds such parts
in a state: ``set_aside`` among the indeterminate directions (analysis/diagnose.py,
model/balances.py), ``near`` along a run (analysis/derivative.py).
"""

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..core.tolerances import ANGLES_IN_NULLSPACE
from .parts.euler_body import proper_euler, singular_values_text
from .parts.part_type import ANGLES


@dataclass(frozen=True)
class AngleSingularity:
    """A part whose ``sequence`` angles are at (or near) their singular position: its middle
    angle ``coordinate`` (``part.angle``) at ``value``; ``direction``: {coordinate: rate}
    of the angle rates that turn nothing there (largest +1)."""

    part: str
    sequence: str
    coordinate: str
    value: float
    direction: dict

    @property
    def angle(self):
        """The middle angle's name within its part."""
        return self.own(self.coordinate)

    @property
    def kind(self):
        """What parts alike share: (sequence, middle angle, the angles that turn about one axis)."""
        return self.sequence, self.angle, tuple(self.own(c) for c in self.direction)

    def own(self, coordinate):
        """``coordinate``'s name within the part (``angle_x`` of ``rear.wheel.angle_x``)."""
        return coordinate.removeprefix(self.part + ".")

    def message(self, where="at"):
        """Which part, where its angles are (``where``: "at", "near" or "approaching") and what to do."""
        return explain([self], where)

    def to_dict(self):
        return dict(part=self.part, sequence=self.sequence, coordinate=self.coordinate, value=self.value,
                    direction=self.direction, message=self.message())


ADVICE = ("use a quaternion body (rotation: quaternion) or another sequence whose singular position the "
          "motion keeps away from")


def explain(singularities, where="at"):
    """One sentence on the AngleSingularity list ``singularities`` — the parts alike (``kind``)
    together — and what to do (ADVICE)."""
    groups = {}
    for a in singularities:
        groups.setdefault(a.kind, []).append(a)
    said = []
    for (sequence, angle, turning), parts in groups.items():
        which = ", ".join(f"{a.part} ({angle} = {a.value:.6g})" for a in parts)
        whose = f"part {which}: its" if len(parts) == 1 else f"parts {which}: their"
        said.append(f"{whose} {sequence} angles are {where} their singular position (singular at {angle} = "
                    f"{singular_values_text(sequence)}, where {' and '.join(turning)} turn about one axis and no "
                    f"angle rates follow every turn of the body)")
    return f"{'; '.join(said)}: {ADVICE}"


class AngleParts:
    """The parts of the model ``system`` that turn by angles, their angles' places in q."""

    def __init__(self, system):
        self.coordinates = list(system.coordinates)
        index = {c: i for i, c in enumerate(self.coordinates)}
        self.parts = [p for p in system.parts if p.part_type.orientation == ANGLES]
        self.angles = np.array([[index[f"{p.name}.{c}"] for c in p.coordinates[3:6]] for p in self.parts],
                               dtype=np.int64).reshape(-1, 3)
        self.middle = self.angles[:, 1].copy()
        self.proper = np.array([proper_euler(p.sequence) for p in self.parts], dtype=np.bool_)

    def __bool__(self):
        return bool(self.parts)

    def distances(self, q):
        """Per part, |det H| at q: |cos| of its middle angle (Tait–Bryan) or |sin| (proper
        Euler), the sine of its distance to the singular position (0 there). ``q`` may be
        longer (a run's stage y, whose first entries are q)."""
        return _distances(q, self.middle, self.proper)

    def nearest(self, q):
        """The least of ``distances`` (np.inf without parts): read at every stage of a run."""
        return _distances(q, self.middle, self.proper).min(initial=np.inf)

    def near(self, q, within):
        """The AngleSingularity of each part whose |det H| at q is below ``within``, nearest first."""
        distances = self.distances(q)
        return [self._singularity(i, q) for i in np.argsort(distances, kind="stable") if distances[i] < within]

    def set_aside(self, q, nullspace):
        """(the AngleSingularity of each part at its singular position at q whose turning-nothing
        direction lies in the span of the orthonormal columns ``nullspace`` (within
        ANGLES_IN_NULLSPACE), the columns spanning the rest of that space)."""
        found, aside = [], []
        for i in range(len(self.parts)):
            w = self._direction(i, q)
            if nullspace.shape[1] and np.linalg.norm(w - nullspace @ (nullspace.T @ w)) <= ANGLES_IN_NULLSPACE:
                found.append(self._singularity(i, q))
                aside.append(nullspace.T @ w)
        if not aside:
            return found, nullspace
        U, s, _ = np.linalg.svd(np.array(aside).T)  # the set-aside directions in the nullspace's coordinates
        kept = int(np.count_nonzero(s > ANGLES_IN_NULLSPACE))
        return found, nullspace @ U[:, kept:]

    def _direction(self, i, q):
        """The unit angle rates that turn part i nothing at q (the null vector of its H), over all coordinates."""
        w = np.zeros(len(self.coordinates))
        w[self.angles[i]] = self.parts[i].singular_direction(q[self.angles[i]])
        return w

    def _singularity(self, i, q):
        part, w = self.parts[i], self._direction(i, q)[self.angles[i]]
        w = w / w[np.argmax(np.abs(w))]
        direction = {self.coordinates[j]: float(x) for j, x in zip(self.angles[i], w) if abs(x) > ANGLES_IN_NULLSPACE}
        return AngleSingularity(part.name, part.sequence, self.coordinates[self.middle[i]], float(q[self.middle[i]]),
                                direction)


@njit(cache=True)
def _distances(q, middle, proper):
    """AngleParts.distances, compiled: a run reads them at every stage."""
    found = np.empty(middle.size)
    for k in range(middle.size):
        found[k] = abs(np.sin(q[middle[k]])) if proper[k] else abs(np.cos(q[middle[k]]))
    return found
