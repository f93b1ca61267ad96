"""The ground floor: errors, the paper's equations (2.14) and (4.24), the linear solvers,
rotations and quaternions, the model files' expression language, where files are kept.
Imports nothing of mbsynth above it."""
