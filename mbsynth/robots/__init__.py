"""Whole robots: URDF read into parts link by link (build.py, urdf.py), their Pinocchio twin
(twin.py) and validation against Pinocchio's reduced-coordinate dynamics and modes."""
