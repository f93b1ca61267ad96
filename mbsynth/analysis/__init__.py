"""What is computed from a model over time or about a state: simulation (the run loop),
projection onto the constraints, linearization, statics, modes, sampled control, and
diagnosis of models whose motion is not unique."""
