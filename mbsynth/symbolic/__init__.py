"""sympy derivation and its compilation to numeric functions (derive.py), kept on disk
between processes (cache.py)."""
