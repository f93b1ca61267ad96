"""The part types a model file names: one record per value of a part's ``type:``.

A ``FileType`` gives the entry's schema ``section`` (schema.py's ``Section``: its keys,
checked by the loader and listed in the model-file reference), its reader ``read(builder,
name, spec, path)`` returning a Part or a list of Parts, and the part types it ``builds``
(model/parts/part_type.py's records: what every other floor asks of the parts it makes).
``FILE_TYPES`` is the one list the loader reads; ``SECTIONS`` is schema.py's sections with
every file type's own. A new way to write a part is a module in io/ holding its reader and
its Section (io/solid.py) and its line in FILE_TYPES; ``type: model`` (a model file as a
substructure) is read by substructures.py, not here.
"""

from typing import Callable, NamedTuple

from ..model.parts import EulerBody, EulerFlexibleBody, FlexibleBody, LagrangianPart, Particle, PlanarBody, RigidBody, Spring
from .flexible import read_flexible_body
from .parts import read_lagrangian, read_particle, read_planar_body, read_rigid_body, read_spring
from .robot import read_robot
from .schema import SECTIONS as _OWN_SECTIONS
from .solid import SOLID, read_solid


class FileType(NamedTuple):
    """One value of ``type:`` (module docstring)."""

    name: str
    section: object  # schema.Section
    read: Callable
    builds: tuple    # PartType records


def file_type(section, read, *classes):
    """The FileType named as its ``section``, whose entries ``read`` reads into parts of ``classes``."""
    return FileType(section.name, section, read, tuple(cls.part_type for cls in classes))


FILE_TYPES = {t.name: t for t in (
    file_type(_OWN_SECTIONS["lagrangian"], read_lagrangian, LagrangianPart),
    file_type(_OWN_SECTIONS["rigid_body"], read_rigid_body, RigidBody, EulerBody),
    file_type(_OWN_SECTIONS["particle"], read_particle, Particle),
    file_type(_OWN_SECTIONS["planar_body"], read_planar_body, PlanarBody),
    file_type(_OWN_SECTIONS["spring"], read_spring, Spring),
    file_type(_OWN_SECTIONS["robot"], read_robot, RigidBody),
    file_type(_OWN_SECTIONS["flexible_body"], read_flexible_body, FlexibleBody, EulerFlexibleBody),
    file_type(SOLID, read_solid, RigidBody),
)}
SECTIONS = {**_OWN_SECTIONS, **{t.section.name: t.section for t in FILE_TYPES.values()}}


def either(names):
    """``a, b or c`` of a list of names (at least one)."""
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"


def file_types_of(test):
    """The names of the file types that build only part types passing ``test`` (a PartType
    predicate): what a message names where such a part is needed."""
    return [t.name for t in FILE_TYPES.values() if all(test(b) for b in t.builds)]
