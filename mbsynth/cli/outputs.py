"""The files a command writes, by one rule for every output flag of every command (each
command module lists its own in ``OUTPUTS``; ``main`` applies the rule):

- before any work, each is checked: its format is its suffix in any case (``run.NPZ`` is
  an .npz file), and it can be written where it is asked for (core.files.unwritable);
  else ModelError naming the flag, the path and why (exit 2);
- when Ctrl-C stops the command, the message says of each what was left: the output so
  far (a file written as the command goes), the file written, or nothing (the file as it
  was, or none). An output made whole at the end is written atomically (never left half
  written); one that grows as the command goes keeps what it had (analysis.trajectory).
"""

from functools import partial
from pathlib import Path
from typing import Callable, NamedTuple

from ..analysis.trajectory import FORMATS, output_file
from ..core.errors import ModelError
from ..core.files import file_format, unwritable


class Output(NamedTuple):
    """An output flag of a command."""

    flag: str  # "--out"
    formats: tuple  # the suffixes it takes (lower case; any case is accepted); (): a folder
    growing: bool = False  # written as the command goes (else whole, once, at the end)
    running: Callable = Path  # value -> the file it is in while the command runs

    def value(self, args):
        """The path given to the flag (None: not given)."""
        return getattr(args, self.flag.lstrip("-").replace("-", "_"), None)

    def check(self, args):
        """ModelError when the path given cannot take this output."""
        value = self.value(args)
        if value is None:
            return
        if self.formats and file_format(value) not in self.formats:
            raise ModelError(f"{self.flag} {value}: the file must end in {', '.join(self.formats)}")
        why = unwritable(value, folder=not self.formats)
        if why:
            raise ModelError(f"{self.flag} {value}: cannot be written there: {why}")


def trajectory_output(flag):
    """A flag taking a trajectory file (.npz or .csv) written as the run goes (while it
    runs, a CSV's rows are in FILE.partial: analysis.trajectory)."""
    return Output(flag, FORMATS, growing=True, running=partial(output_file, completed=False))


class Outputs:
    """A command's output files as they were when it started."""

    def __init__(self, args, outputs):
        self.outputs = [output for output in outputs if output.value(args) is not None]
        self.args = args
        self.paths = [Path(output.running(output.value(args))) for output in self.outputs]
        self.before = [_state(path) for path in self.paths]

    def check(self):
        """Every output flag given checked (Output.check) before the command runs."""
        for output in self.outputs:
            output.check(self.args)

    def left(self):
        """What an interrupted command left of each output, as the end of its message:
        "; the output so far is in FILE" (or "; FILE was written"), "; nothing was written
        to FILE", "; nothing was written (FILE is as it was)"."""
        said = []
        for output, path, before in zip(self.outputs, self.paths, self.before):
            now = _state(path)
            if now is None:
                said.append(f"nothing was written to {path}")
            elif now == before:
                said.append(f"nothing was written ({path} is as it was)")
            else:
                said.append(f"the output so far is in {path}" if output.growing else f"{path} was written")
        return "".join(f"; {words}" for words in said)


def _state(path):
    """What identifies the file (or folder) at ``path`` now (inode, mtime, size); None where there is none."""
    try:
        stat = path.stat()
    except OSError:
        return None
    return stat.st_ino, stat.st_mtime_ns, stat.st_size
