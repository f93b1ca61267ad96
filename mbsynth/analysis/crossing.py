"""Stepping across a singular position: one step straddles it, its stages put on the constraints.

At a singular position t* the rows of A lose rank for an instant (a parallelogram's change
points). Near it the index-1 equations amplify any drift of a state off the manifold: with
σ the vanishing singular value, a position drift ε makes the velocity rows turn the motion
along the nearly free direction at a rate of about ε/σ² and its acceleration ε/σ³ (the
level sets of φ near a saddle of the constraints are hyperbolas that join the branches).
An explicit integrator whose stages come near t* chases that with ever smaller steps (the
crawl of derivative.py), at any tolerance tight enough to see the drift of rounding.

So the run plans its steps (``Crossing.plan``): from the measure m(t) at each accepted
step's end (σ_r/σ₁ of A, its rows scaled to unit norm: singular_watch.py's for a small
model, compiled/least_direction.py's from the kernel's rows for a large one), which falls
like |t − t*| towards a singular position, t* is predicted by the line through the last two
ends. When the next step would reach it, the step is aimed to end where the following one,
of the length h the integrator proposes, has t* at the fraction θ* of the method's step
that lies farthest from every node c_i at which it evaluates a stage (0.47 of a DOP853
step, whose nodes then stay 0.13 h from t*). That step, across t*, evaluates each stage at
the state put on the constraints first (derivative.StateDerivative.on_manifold): it
integrates ẏ = g(P(y)), which on the manifold is the motion itself and, off it, is smooth
where g is not. The branch the motion is on continues through t* (its velocity keeps it
there: the other branch meets it at an angle).
"""

import numpy as np

PLAN_BELOW = 0.5  # m below which a falling measure is taken as a singular position ahead
NAMED_SHARE = 0.1  # a crossing lists the rows whose weight in its least direction exceeds this share of the largest
PRE_STEP = 0.1  # t* farther than θ* h by this share of h: a step first ends at t* − θ* h


RADAU_NODES = ((4 - 6**0.5) / 10, (4 + 6**0.5) / 10, 1.0)  # Radau IIA (order 5)'s collocation points


def nodes(method):
    """The fractions of a step of ``method`` (an explicit Runge–Kutta pair, or Radau IIA) at
    which it evaluates a stage (C, and C_EXTRA for its interpolant; Radau's collocation
    points), with 0 and 1, sorted."""
    stages = getattr(method, "C", RADAU_NODES)
    return np.unique(np.concatenate([[0.0, 1.0], stages, getattr(method, "C_EXTRA", [])]))


class Crossing:
    """The step plan of a run integrated by ``method`` near singular positions."""

    def __init__(self, method):
        self.nodes = nodes(method)
        gaps = np.diff(self.nodes)
        widest = int(np.argmax(gaps))
        self.theta = float(self.nodes[widest] + gaps[widest] / 2)  # θ*: farthest from every node
        self.ends = []  # the last two accepted ends: (t, m)

    def restart(self):
        """Forget the ends: the run goes on from a state not reached by a planned step."""
        self.ends = []

    def passed(self, t, m):
        """An accepted step ended at t, its measure m there."""
        self.ends = self.ends[-1:] + [(t, m)]

    def plan(self, t, h, bound):
        """(where the next step from t should end, whether it crosses a singular position)
        for a step the integrator proposes of length h, bound by ``bound``; (None, False):
        as the integrator chooses. Where t* lies beyond θ* h (by PRE_STEP h), the step ends
        at t* − θ* h, for the next one to cross it at θ*; nearer, the step across it from t
        is the one (``across``) that keeps its nodes farthest from it."""
        if len(self.ends) < 2 or self.ends[-1][0] != t:
            return None, False
        (t0, m0), (t1, m1) = self.ends
        if not (m1 < m0 and m1 < PLAN_BELOW):
            return None, False
        d = m1 * (t1 - t0) / (m0 - m1)  # t* − t: the line through the two ends meets m = 0
        if d - self.theta * h > PRE_STEP * h:
            return (t + d - self.theta * h, False) if d - self.theta * h < h else (None, False)
        end = t + self.across(d, h)
        return (end, True) if end <= bound else (None, False)

    def crossed(self):
        """t* of the singular position between the last two ends, one on either side of it:
        where m = k |t − t*| meets both."""
        (t0, m0), (t1, m1) = self.ends
        return (m1 * t0 + m0 * t1) / (m0 + m1)

    def across(self, d, h):
        """The length H ≤ h (h > d) of a step that crosses t* at d from its start whose nodes
        lie farthest from t*: h itself, or t* at the centre of the gap between two nodes
        (H = 2d / (c_k + c_k+1)), whichever leaves the widest distance."""
        a, b = self.nodes[:-1], self.nodes[1:]
        lengths = np.append(2 * d / (a + b), h)
        distance = np.append(d * (b - a) / (a + b), np.abs(d - self.nodes * h).min())
        distance[lengths > h] = -1.0
        return float(lengths[int(np.argmax(distance))])
