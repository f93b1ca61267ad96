"""The old names of model-file keys, still read: each one the same key as its new name.

A file may use either name of a key, not both (``ModelError`` at the old one's line)."""

from ..core.errors import ModelError

OLD_KEYS = {"subsystems": "parts", "closure": "balances"}  # old name -> the key's name


def renamed(root, name):
    """``root`` (a file's top-level LineDict) with each old key under its new name, in its
    place and with its line; ``name``: the file's, for the error."""
    found = [old for old in OLD_KEYS if old in root]
    if not found:
        return root
    for old in found:
        if OLD_KEYS[old] in root:
            raise ModelError(f"{name}:{root.key_lines[old]}: at {old}: '{old}' is the old name of "
                             f"'{OLD_KEYS[old]}' (line {root.key_lines[OLD_KEYS[old]]}); give one of them")
    new = type(root)()
    new.line, new.key_lines = root.line, {}
    for key, value in root.items():
        key_name = OLD_KEYS.get(key, key)
        new[key_name], new.key_lines[key_name] = value, root.key_lines[key]
    return new
