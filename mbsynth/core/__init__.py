"""The ground floor: errors, the paper's equations (2.14) and (4.24), the linear solvers,
rotations and quaternions, the model files' expression language, where files are kept, the
table of joint kinds.
Imports nothing of mbsynth above it."""
