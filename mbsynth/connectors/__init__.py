"""Constraints that join parts: each knows the coordinates it couples and returns its
rows of A and b (2.4), its share of the non-ideal force C (2.6), and its residuals
φ and φ̇ for drift control."""

from ..constraint import Connector
from .joints import JOINT_KINDS, Joint

__all__ = ["Connector", "Joint", "JOINT_KINDS"]
