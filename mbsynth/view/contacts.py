"""What the viewer draws of a run's contacts: at each impact, where it struck and its impulse.

For every contact (``System.unilaterals`` of kind "contact", whose ``point`` and ``normal``
the model file gives) that has events with an impulse (``Trajectory.events`` of kind
"impact" or "contact", analysis/impacts.py), two nodes under ``contacts/<name>/``:

- ``point``: a sphere at the contact point;
- ``impulse``: an arrow from the point along the contact's normal (the direction the
  impulse pushes), its length the impulse Λ times one scale for the whole run, so that the
  largest impulse of the run is ``IMPULSE_LENGTH`` of the model's length: arrows are
  proportional to their impulses.

Each shows for ``EVENT_SHOW`` seconds of motion from its event (the drawn rows in
[t_e, t_e + EVENT_SHOW), at least the first drawn row at or after t_e), the latest event
of its contact winning; at other rows scene.py draws both at a vanishing scale. The positions
at an event come from the trajectory's rows before it (``position_at``).
"""

from typing import NamedTuple

import numpy as np
import sympy as sp

from ..symbolic.derive import T_SYMBOL, compile_function

CONTACT_COLOR = [0.85, 0.1, 0.1, 1.0]
POINT_RADIUS = 0.015  # the contact point's sphere, of the model's length
ARROW_RADIUS = 0.006  # the arrow's shaft, of the model's length
IMPULSE_LENGTH = 0.3  # the largest impulse's arrow, of the model's length
EVENT_SHOW = 0.2  # seconds of motion an impact stays drawn
STRUCK = ("impact", "contact")  # the events whose impulse is drawn (normal impulses)


class Drawn(NamedTuple):
    """A contact's node: its ``path``, ``shapes``, per drawn row its ``start`` (and ``end``
    for an arrow, None for a point) and whether it is ``shown``."""

    path: str
    shapes: list
    start: np.ndarray
    end: np.ndarray
    shown: np.ndarray


def contact_items(system, trajectory, times, length):
    """The ``Drawn`` contact points and impulse arrows at ``times`` (the drawn rows' times)
    of a model of length ``length``; none where the run had no impulse at a contact."""
    contacts = {u.name: u for u in system.unilaterals if u.kind == "contact" and u.point is not None}
    events = [ev for ev in trajectory.events if ev.name in contacts and ev.kind in STRUCK and ev.impulse > 0]
    if not events:
        return []
    scale = IMPULSE_LENGTH * length / max(ev.impulse for ev in events)
    items = []
    for name, contact in contacts.items():
        own = sorted((ev for ev in events if ev.name == name), key=lambda ev: ev.t)
        if not own:
            continue
        points, tips = np.zeros((len(times), 3)), np.zeros((len(times), 3))
        shown = np.zeros(len(times), dtype=bool)
        for ev, (point, normal) in zip(own, _locate(system, trajectory, contact, [ev.t for ev in own])):
            rows = shown_rows(times, ev.t)
            points[rows], tips[rows], shown[rows] = point, point + scale * ev.impulse * normal, True
        items.append(Drawn(f"contacts/{name}/point",
                           [{"shape": "sphere", "size": [POINT_RADIUS * length], "color": CONTACT_COLOR}],
                           points, None, shown))
        items.append(Drawn(f"contacts/{name}/impulse",
                           [{"shape": "arrow", "size": [ARROW_RADIUS * length], "color": CONTACT_COLOR}],
                           points, tips, shown))
    return items


def shown_rows(times, t_event):
    """The indices of the drawn ``times`` at which an event at ``t_event`` is drawn: those in
    [t_e, t_e + EVENT_SHOW), at least the first at or after t_e (none after the last)."""
    rows = np.flatnonzero((times >= t_event) & (times < t_event + EVENT_SHOW))
    if len(rows) == 0:
        later = np.flatnonzero(times >= t_event)
        rows = later[:1]
    return rows


def position_at(trajectory, t):
    """q at time t from the rows at or before it (positions are continuous at an impact, velocities
    are not): the cubic through the last two rows' q and q̇ (exact for a free fall), or the
    first row's q + q̇ (t − t0) where t is before the second row."""
    times, q, qd = trajectory.t, np.asarray(trajectory.q), np.asarray(trajectory.qd)
    i = int(np.searchsorted(times, t, side="right")) - 1
    if i < 1:
        return q[0] + qd[0] * (t - times[0])
    h = times[i] - times[i - 1]
    s = (t - times[i - 1]) / h
    return ((2 * s**3 - 3 * s**2 + 1) * q[i - 1] + (s**3 - 2 * s**2 + s) * h * qd[i - 1]
            + (-2 * s**3 + 3 * s**2) * q[i] + (s**3 - s**2) * h * qd[i])


def _locate(system, trajectory, contact, event_times):
    """[(contact point, unit normal)] of ``contact`` at each of ``event_times``."""
    f = compile_function((T_SYMBOL, list(system.q_symbols), system.parameter_symbols),
                         [sp.Matrix(contact.point), sp.Matrix(contact.normal)])
    p = system.parameter_values
    found = []
    for t in event_times:
        point, normal = f(t, position_at(trajectory, t), p)
        normal = np.ravel(normal)
        found.append((np.ravel(point), normal / np.linalg.norm(normal)))
    return found
