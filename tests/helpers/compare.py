"""How far apart two numbers are, for the tests' assertions."""

import numpy as np


def rel(x, y):
    """‖x − y‖ / ‖y‖ (2-norm of the flattened arrays), ‖x‖ itself where y is zero."""
    return np.linalg.norm(np.asarray(x) - np.asarray(y)) / max(np.linalg.norm(y), 1e-300)
