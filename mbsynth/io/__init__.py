"""Reading models from files."""

from .loader import load, loads

__all__ = ["load", "loads"]
