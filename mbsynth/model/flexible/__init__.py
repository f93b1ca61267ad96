"""The finite-element layer of flexible bodies: an FE model's matrices and nodes
(matrices.py), read from files (files.py) or generated for a straight 3D beam (beam.py),
reduced to interface and modal coordinates by Craig–Bampton or free-interface modes
(reduction.py), and the floating-frame inertia invariants of a reduced model
(invariants.py). Numbers only: no part type and no model-file key is defined here; a
flexible part is built on this API (each module's docstring states its contract)."""
