"""The production path of System.motion: linear-time assembly and solve in numba."""
