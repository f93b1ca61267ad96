"""Composing a model in Python from model files, as a model file composes them.

    import mbsynth as mb
    robot = mb.compose(
        {"torso": {"type": "rigid_body", "mass": 8, "inertia": [0.1, 0.2, 0.2]},
         "leg": mb.substructure("leg.yaml", parameters={"L": 0.4}, placement={"position": [0.2, 0, 0]},
                                count=4)},
        joints=[{"name": "hip", "for": {"i": [0, 3]}, "type": "revolute", "parent": "torso",
                 "child": "leg[i].hip"}],
        gravity=[0, 0, -9.81])

``compose`` takes the keys of a model file's top level as arguments and builds the System
exactly as ``mb.loads`` of that file would (the same checks, names and order); file names
are relative to ``folder`` (default: the working folder). Its error messages name the model
text it wrote (``System.source`` holds it).
"""

import warnings
from pathlib import Path

import yaml

from ..core.errors import ModelError
from .loader import loads
from .old_keys import OLD_KEYS

TOP_KEYS = ("parameters", "gravity", "world", "constraints", "joints", "balances", "initial", "initial_fixed",
            "forces", "outputs", "ports")


def substructure(file, parameters=None, placement=None, count=None):
    """The entry of a model file used as a part (``type: model``): ``parameters`` {name:
    value or expression}, ``placement`` {position, rpy | axis | quaternion}, ``count``."""
    entry = {"type": "model", "file": str(file)}
    for key, value in (("parameters", parameters), ("placement", placement), ("count", count)):
        if value is not None:
            entry[key] = value
    return entry


def compose(parts=None, joints=None, *, name="composed", folder=None, load_parameters=None, **keys):
    """The System of a model whose top level is ``parts`` ({name: part or
    ``substructure(...)``}), ``joints`` and the other top-level keys of a model file
    (``parameters``, ``gravity``, ``world``, ``constraints``, ``balances``, ``initial``,
    ``initial_fixed``, ``forces``, ``outputs``, ``ports``); ``load_parameters``: as
    ``parameters=`` of ``mb.load``. A key's old name (io/old_keys.py) is read as the key, with a
    DeprecationWarning."""
    keys["parts"] = parts
    for old in sorted(set(keys) & set(OLD_KEYS)):
        new = OLD_KEYS[old]
        warnings.warn(f"compose({old}=) is the old name of compose({new}=)", DeprecationWarning, stacklevel=2)
        if keys.get(new) is not None:
            raise ModelError(f"compose(): {new}= and its old name {old}= given both; give {new}= only")
        keys[new] = keys.pop(old)
    parts = keys.pop("parts")
    unknown = sorted(set(keys) - set(TOP_KEYS))
    if unknown:
        raise ModelError(f"compose(): unknown model key(s) {unknown}; allowed: {', '.join(TOP_KEYS)}")
    model = {"name": name, **{key: keys[key] for key in TOP_KEYS if keys.get(key) is not None},
             "parts": parts}
    if joints is not None:
        model["joints"] = joints
    try:
        text = yaml.safe_dump(_plain(model), sort_keys=False, width=1_000)
    except yaml.YAMLError as err:
        raise ModelError(f"compose(): the model holds something a model file cannot: {err}") from None
    folder = Path.cwd() if folder is None else Path(folder)
    return loads(text, name=f"<compose {name}>", folder=folder, parameters=load_parameters)


def _plain(value):
    """``value`` with paths, tuples and numpy numbers as YAML's plain types."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "item") and callable(value.item):  # a numpy scalar
        return value.item()
    return value
