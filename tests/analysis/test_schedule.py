"""The run's stop times (mbsynth.analysis.schedule) against the sets they stand for: the
output times and the control samples t0 + j h in [t0, t_end), merged."""

import itertools
import tracemalloc

import numpy as np
import pytest

from mbsynth.analysis.schedule import Schedule


@pytest.mark.parametrize("t0, t_end, dt, h", [
    (0.0, 0.2, 0.004, 0.01), (0.3, 1.0, 0.1, 0.03), (0.0, 1.0, 0.1, None), (-1.0, 1.0, 0.5, 0.5), (0.0, 1.0, 0.25, 0.7),
    pytest.param(0.0, 2.0, 0.004, 0.01, marks=pytest.mark.slow),  # 700 stops: every pair of them, seconds of Python
])
def test_the_stops_are_the_outputs_and_samples_merged(t0, t_end, dt, h):
    outputs = np.append(np.arange(t0, t_end, dt), t_end)
    samples = [] if h is None else [t0 + h * j for j in range(int(np.ceil((t_end - t0) / h - 1e-9)))]
    schedule = Schedule(outputs, h)
    expected = sorted(set(outputs.tolist()) | set(samples))
    stops = list(schedule)
    assert [t for t, _, _ in stops] == expected[1:]  # t0 is where the run starts
    assert all(is_output == (t in set(outputs.tolist())) and is_sample == (t in set(samples))
               for t, is_output, is_sample in stops)
    for t in expected:
        later = [s for s in samples if s >= t]
        assert schedule.next_stop(t) == (later[0] if later else t_end)
    for a, b in itertools.combinations(expected, 2):
        assert schedule.between(a, b) == [t for t in expected if a <= t < b]


def test_a_short_control_interval_takes_no_memory():
    """A billion samples (h = 1e-9 over 1 s) are computed as they come: making the schedule
    and walking into it allocates next to nothing."""
    h = 1e-9
    tracemalloc.start()
    schedule = Schedule(np.linspace(0.0, 1.0, 11), h)
    first = [t for t, _, _ in itertools.islice(schedule, 3)]
    found = schedule.between(0.1, 0.1 + 2.5e-9)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 100_000
    assert first == [h, 2 * h, 3 * h]
    j0 = round(0.1 / h)
    assert found == sorted({0.1} | {h * j for j in range(j0 - 3, j0 + 4) if 0.1 <= h * j < 0.1 + 2.5e-9})
    assert len(found) in (3, 4) and schedule.next_stop(0.5) == min(h * j for j in range(j0 * 5 - 3, j0 * 5 + 4)
                                                                   if h * j >= 0.5)
