"""Constraints that join parts: each knows the coordinates it couples and returns its
rows of A and b (2.4), its share of the non-ideal force C (2.6), and its residuals
φ and φ̇ for drift control. base.py: the Constraint; joints.py: joints between frames
(their kinds: core/joint_kinds.py); rolling.py: rolling disks and knife edges."""
