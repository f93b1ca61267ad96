"""The kinds of error a user of mbsynth can cause, and the verdicts that are no fault."""


class ModelError(ValueError):
    """Bad model input: a file, key, name, expression or value that cannot be used.

    The message names the file and line, the key path, the part or the coordinate.
    """


class SolveError(ArithmeticError):
    """The data at a state admit no motion: contradictory constraints, a force on a
    direction no mass resists (w^T (Q + C) != 0, w in null [M; A]), or NaN/inf input.

    ``constraints`` and ``coordinates`` name the offenders where they are known.
    """

    def __init__(self, message, *, constraints=(), coordinates=()):
        super().__init__(message)
        self.constraints = tuple(constraints)
        self.coordinates = tuple(coordinates)


class EventError(SolveError):
    """No motion through an event of a limit or contact (analysis/impacts.py): a velocity
    jump that is not unique, no consistent impact or contact mode, gaps that chatter. Found
    at its time, it stops the run there (an interval integrated again cannot avoid it)."""


class NoEquilibrium(SolveError):
    """A verdict, not a fault: the model has no rest where one is asked for — no static
    equilibrium found from the given configuration, one that is not isolated
    (analysis/statics.py), or a state given to ``modes`` that is not at rest. The command
    line exits 1 for it."""


class SimulationError(SolveError):
    """A run that had to stop (no motion at a state, a NaN/inf or exploding state, a
    step-size collapse). ``time`` is where it stopped and ``trajectory`` holds every
    output row computed before, the last good state included (saved when an output
    file was asked for)."""

    def __init__(self, message, *, time, trajectory, constraints=(), coordinates=()):
        super().__init__(message, constraints=constraints, coordinates=coordinates)
        self.time = time
        self.trajectory = trajectory


class ControlError(ModelError):
    """A run's controller failed at a sample: it raised (the cause is chained) or gave a
    value the model cannot take. ``time`` is the sample's time and ``trajectory`` holds
    every output row computed before (saved when an output file was asked for)."""

    def __init__(self, message, *, time, trajectory=None):
        super().__init__(message)
        self.time = time
        self.trajectory = trajectory
