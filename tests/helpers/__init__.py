"""What several test files share, imported as ``tests.helpers.<module>`` (the repository root
is on pytest's path: pyproject's ``pythonpath``):

    compare.py          ``rel``: the relative difference of two arrays
    states.py           ``random_state``: random coordinates and velocities of a System
    literal.py          (2.14) written out in numpy, independent of equations.py
    rotations.py        quaternion kinematics written from the formulas
    flexible_beams.py   a steel strip, Euler–Bernoulli frequencies, a point-mass truss
    n_four_bar_files.py the N-four-bar as a cell file used N times, and a nested model
    processes.py        finding and waiting for processes (servers a command starts)
"""
