"""The model: parts (parts/), constraints (constraints/), force elements, the System (a
value) and its Data (the workspace of a computation), the evaluation of their arrays, joint
values, reactions, outputs, and the force balances of massless parts (balances.py)."""
