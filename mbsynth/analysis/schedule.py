"""The times a run stops at: its output times and its control samples, merged, in order.

Output times are kept as an array (the run keeps a row for each: recording.py); control
samples t0 + j h are computed as they come, so a short control interval costs no memory.
"""

import math

import numpy as np
from ..core.tolerances import SAMPLE_ROUNDING


class Schedule:
    """Output ``times`` (an increasing array, from t0 to t_end) and control samples every
    ``sample_dt`` from t0 (None: none), in [t0, t_end)."""

    def __init__(self, times, sample_dt=None):
        self.outputs = np.asarray(times, dtype=float)
        self.t0, self.t_end = float(self.outputs[0]), float(self.outputs[-1])
        self.h = None if sample_dt is None else float(sample_dt)
        span = self.t_end - self.t0
        self.count = 0 if self.h is None else int(np.ceil(span / self.h - SAMPLE_ROUNDING))  # samples in [t0, t_end)
        self.skipped = None  # ``skip_through``'s time, for the iteration to go on after

    def sample(self, j):
        """The time of sample j."""
        return self.t0 + self.h * j

    def _first_sample_from(self, t):
        """The index of the first sample at or after t (``count`` where none is)."""
        if self.h is None:
            return 0
        j = max(0, min(self.count, math.floor((t - self.t0) / self.h)))
        while j < self.count and self.sample(j) < t:
            j += 1
        while j > 0 and self.sample(j - 1) >= t:
            j -= 1
        return j

    def __iter__(self):
        """(t, is_output, is_sample) for every time after t0, in order."""
        i, j = 1, self._first_sample_from(self.t0) + (1 if self.count else 0)
        outputs = self.outputs
        while i < len(outputs) or j < self.count:
            t_out = outputs[i] if i < len(outputs) else np.inf
            t_sample = self.sample(j) if j < self.count else np.inf
            t = min(t_out, t_sample)
            yield float(t), t == t_out, t == t_sample
            i += t == t_out
            j += t == t_sample
            if self.skipped is not None:
                i = max(i, int(np.searchsorted(outputs, self.skipped, side="right")))
                j = max(j, self._first_sample_from(np.nextafter(self.skipped, np.inf)))
                self.skipped = None

    def skip_through(self, t):
        """Go on, in the iteration under way, from the first time after t (the times up to t
        were dealt with at once)."""
        self.skipped = t

    def next_stop(self, t):
        """The first control sample at or after t, or t_end: where a continuous integrator
        must stop (the forces jump, or the run ends)."""
        j = self._first_sample_from(t)
        return self.sample(j) if j < self.count else self.t_end

    def between(self, a, b):
        """The output times and samples in [a, b), in order."""
        outputs = self.outputs[self.outputs.searchsorted(a):self.outputs.searchsorted(b)].tolist()
        if self.h is None:
            return outputs
        j, samples = self._first_sample_from(a), []
        while j < self.count and self.sample(j) < b:
            samples.append(self.sample(j))
            j += 1
        return sorted(set(outputs) | set(samples))
