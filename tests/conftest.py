"""Shared by every test folder (one per floor of the package): the helpers beside this file
(literal.py: the literal pseudo-inverse form of (2.14); rotations.py: rotation matrices and
quaternion rate matrices written out by hand) import by their names."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
