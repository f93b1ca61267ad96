"""Reading what the viewer builds, for the tests of mbsynth.view: trajectories to draw,
a scene's nodes, segments' ends and the animation in meshcat's page."""

import base64
import re

import numpy as np
import umsgpack

from mbsynth.analysis.trajectory import Trajectory


def trajectory_of(system, q):
    """A Trajectory with the given rows of coordinates (times 0, 1, ...)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = len(q)
    return Trajectory(system.coordinates, np.arange(n, dtype=float), q, np.zeros_like(q), *np.zeros((4, n)))


def node(scene, path):
    """The one node of ``scene`` at ``path``."""
    (found,) = [n for n in scene.nodes if n.path == path]
    return found


def segment_ends(T):
    """Where a segment transform T (scene.segment_transforms) puts (0, 0, 0) and (1, 0, 0)."""
    return (T @ [0, 0, 0, 1])[:3], (T @ [1, 0, 0, 1])[:3]


def animation_clips(html):
    """{path: {track: (times, values)}} of the set_animation command in meshcat's page."""
    commands = [umsgpack.unpackb(base64.b64decode(blob))
                for blob in re.findall(r'data:application/octet-binary;base64,([A-Za-z0-9+/=]+)', html)]
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    clips = {}
    for entry in animation["animations"]:
        path = entry["path"] if isinstance(entry["path"], str) else "/" + "/".join(entry["path"])
        clips[path] = {track["name"].lstrip("."): (np.array([k["time"] for k in track["keys"]]),
                                                   np.array([k["value"] for k in track["keys"]]))
                       for track in entry["clip"]["tracks"]}
    return clips
