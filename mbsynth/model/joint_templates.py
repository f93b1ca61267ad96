"""Derivations shared by joints alike: a joint's rows (constraints/joints.py) and its values
and reaction frame (joint_values.py).

What a joint derives depends on its kind, the types of its two parts (and their numbers of
coordinates) and its frames' offsets and rotations. Joints between parts whose poses depend on
their coordinates alone (their type's ``shared_pose``), with frames fixed on them, share one derivation,
a template: derived with the frames' entries as placeholder symbols and the parts'
coordinates and velocities as slots, once per process and kept on disk
(symbolic.cache.remembered); each joint then puts in its frames' values (``constants``) and
its own coordinates (symbolic.derive.placed_values, compile_function's constants).
"""

from typing import NamedTuple

import sympy as sp

from ..symbolic.cache import placeholder, remembered
from ..symbolic.derive import Slots
from .parts import Frame


class Placeholders(NamedTuple):
    """What a template is derived in: the two parts' coordinates ``q`` and velocities ``qd``
    (parent's then child's), their ``slots`` (q slots, q̇ slots), ``to_slots`` ({q, q̇: slot})
    and the placeholder ``frames`` (one per end)."""

    q: list
    qd: list
    slots: tuple
    to_slots: dict
    frames: list


class Templates:
    """The templates of one derivation: ``derive(kind, parent, child, placeholders, *extra)``
    returns a tuple of expressions in the placeholders (kept on disk as ``tag``-...). ``ends``
    names the frames a joint passes ("AB": its two frames, "ABR": and its reaction frame)."""

    def __init__(self, tag, ends, derive):
        self.tag, self.derive, self.kept = tag, derive, {}
        self.placeholders = [tuple(placeholder(f"{tag}_{end}{i}") for i in range(12)) for end in ends]
        self.frames = [Frame("", "", sp.Matrix(x[:3]), sp.Matrix(3, 3, x[3:])) for x in self.placeholders]
        self.slots = Slots(f"{tag}_q"), Slots(f"{tag}_qd")

    def __call__(self, kind, parent, child, *extra):
        """The template of joints of ``kind`` between parts of the types of ``parent`` and
        ``child`` (and alike in ``extra``), derived from these two the first time."""
        key = (kind, type(parent), len(parent.q) if parent is not None else 0, type(child), len(child.q), *extra)
        if key not in self.kept:
            names = (kind, type(parent).__qualname__, key[2], type(child).__qualname__, key[4], *extra)
            self.kept[key] = remembered(self.tag, names, lambda: self._derive(kind, parent, child, extra))
        return self.kept[key]

    def _derive(self, kind, parent, child, extra):
        q, qd = joint_coordinates(parent, child)
        slots = (tuple(self.slots[0][i] for i in range(len(q))), tuple(self.slots[1][i] for i in range(len(q))))
        to_slots = dict(zip(q + qd, slots[0] + slots[1]))
        return self.derive(kind, parent, child, Placeholders(q, qd, slots, to_slots, self.frames), *extra)

    def constants(self, frames, moving):
        """{placeholder: entry} of ``frames`` (one per end, in the order of ``ends``), or None
        when an entry holds a symbol in ``moving`` (a frame that moves on its part)."""
        found = {}
        for names, frame in zip(self.placeholders, frames):
            entries = list(frame.position) + list(frame.rotation)
            if any(x in moving for e in entries for x in sp.sympify(e).free_symbols):
                return None
            found.update(zip(names, entries))
        return found


def shared(*parts):
    """Whether joints on ``parts`` (None: the world) may take a template."""
    return all(p.part_type.shared_pose for p in parts if p is not None)


def joint_coordinates(parent, child):
    """(q, q̇) of a joint's two parts, parent's (none for the world) then child's, as lists."""
    return ((list(parent.q) if parent is not None else []) + list(child.q),
            (list(parent.qd) if parent is not None else []) + list(child.qd))


def pose(part, frame):
    """(origin, rotation) of ``frame`` in the world, on ``part`` or (None) fixed in the world."""
    if part is None:
        return sp.Matrix(frame.position), sp.Matrix(frame.rotation)
    return part.pose(frame)
