"""Distances to segments in closed form, as sympy expressions: the gaps of a sphere and of
a capsule against a capsule (io/unilateral.py) are such a distance less both radii, a
holonomic row whose a and b come from differentiating it (model/unilateral.py). Each is a
Piecewise of smooth branches, each branch differentiated on its own."""

import sympy as sp

from ..core.tolerances import DIVISION_GUARD, PARALLEL_SIN2


def clamp(x, half):
    """x held to [−half, half] (a Piecewise of three smooth branches)."""
    return sp.Piecewise((-half, x < -half), (half, x > half), (x, True))


def to_segment(p, c, axis, half):
    """(the distance from p to the segment c + s·axis, |s| ≤ ``half`` (axis a unit column),
    its point nearest to p): with s = (p − c)·axis, |p − c ∓ half·axis| beyond an end, else
    |p − c − s·axis| (one Piecewise of three smooth branches)."""
    s = (p - c).dot(axis)
    ends = (c - half * axis, c + half * axis)
    distance = sp.Piecewise((_length(p - ends[0]), s < -half), (_length(p - ends[1]), s > half),
                            (_to_line(p, c, axis), True))
    nearest = sp.Matrix([sp.Piecewise((ends[0][k], s < -half), (ends[1][k], s > half), (c[k] + s * axis[k], True))
                         for k in range(3)])
    return distance, nearest


def between_segments(c1, d1, h1, c2, d2, h2):
    """(distance, the first's nearest point, the second's) of the segments c1 + s d1,
    |s| ≤ h1, and c2 + t d2, |t| ≤ h2 (d1, d2 unit columns), by the clamped solution: s of
    the lines' nearest pair, (n × d2)·r / |n|² (n = d1 × d2, r = c1 − c2), clamped to the
    first; t = d2·(r + s d1); where t is beyond an end of the second, that end against the
    first (``to_segment``). The distance is one flat Piecewise, each branch its own closed
    form (the lines' |r·n| / |n|, a point's to a line, two points'), its conditions free of
    Piecewise and of divisions.

    The segments are parallel where sin² of their angle, |n|², is below PARALLEL_SIN2: s is
    then the projection of the second's centre on the first, clamped to it. Parallel
    segments that overlap along their length are at the same distance over the whole
    overlap: the gap is that distance, one row, its point on the first nearest the second's
    centre (in the overlap). Near parallel the nearest pair is the lines' own, which slides
    along the overlap ~1/sin as fast as the axes turn."""
    r = c1 - c2
    b, c, f = d1.dot(d2), d1.dot(r), d2.dot(r)
    n = d1.cross(d2)
    sin2 = n.dot(n)
    parallel = sin2 < PARALLEL_SIN2
    along1, along2 = n.cross(d2).dot(r), n.cross(d1).dot(r)  # |n|² × the lines' nearest s and t
    # s clamped below and above (parallel, apart: the second's projection [−c − h2, −c + h2] beyond an end)
    low = (parallel & (h2 - c < -h1)) | (~parallel & (along1 < -h1 * sin2))
    high = (parallel & (-h2 - c > h1)) | (~parallel & (along1 > h1 * sin2))
    lines = ~parallel & ~low & ~high
    # t = d2·(r + s d1) beyond the second's ends
    t_low = (low & (f - b * h1 < -h2)) | (high & (f + b * h1 < -h2)) | (lines & (along2 < -h2 * sin2))
    t_high = (low & (f - b * h1 > h2)) | (high & (f + b * h1 > h2)) | (lines & (along2 > h2 * sin2))
    # parallel and overlapping: the first's point nearest the second's centre (its projection −c, clamped)
    low |= parallel & (-c < -h1)
    high |= parallel & (-c > h1)
    ends1, ends2 = (c1 - h1 * d1, c1 + h1 * d1), (c2 - h2 * d2, c2 + h2 * d2)
    branches = [branch for end, beyond in zip(ends2, (t_low, t_high)) for branch in _end_against(end, c1, d1, h1,
                                                                                                  beyond)]
    branches += [(_to_line(ends1[0], c2, d2), low), (_to_line(ends1[1], c2, d2), high),
                 (_to_line(c2, c1, d1), parallel)]
    distance = sp.Piecewise(*branches, (sp.sqrt(r.dot(n) ** 2 / (sin2 + DIVISION_GUARD)), True))
    s = sp.Piecewise((-h1, low), (h1, high), (-c, parallel), (along1 / (sin2 + DIVISION_GUARD), True))
    t = clamp(b * s + f, h2)
    (_, on_below), (_, on_above) = (to_segment(end, c1, d1, h1) for end in ends2)
    first = sp.Matrix([sp.Piecewise((on_below[k], t_low), (on_above[k], t_high), (c1[k] + s * d1[k], True))
                       for k in range(3)])
    second = sp.Matrix([sp.Piecewise((ends2[0][k], t_low), (ends2[1][k], t_high), (c2[k] + t * d2[k], True))
                        for k in range(3)])
    return distance, first, second


def _end_against(p, c, axis, half, where):
    """``to_segment``'s distance from p to the segment as flat branches, each also ``where``."""
    s = (p - c).dot(axis)
    return [(_length(p - c + half * axis), where & (s < -half)), (_length(p - c - half * axis), where & (s > half)),
            (_to_line(p, c, axis), where)]


def _to_line(p, c, axis):
    """The distance from p to the line c + s·axis (axis a unit column)."""
    return _length(p - c - (p - c).dot(axis) * axis)


def _length(v):
    return sp.sqrt(v.dot(v))
