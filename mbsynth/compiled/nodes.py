"""The kinds of node the compiled kernel knows (layout.py), named by each part type's record
(model/parts/part_type.py: ``node``); a module of its own so that naming them loads no kernel."""

RIGID_NODE, PARTICLE_NODE, EXTRA_NODE = "rigid", "particle", "extra"  # extra: coordinates of the Schur system
