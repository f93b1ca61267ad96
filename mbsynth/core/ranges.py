"""``NAME=START:STOP:COUNT``: a parameter's range as written on the command line (``mbsynth
sweep --param``, ``mbsynth modes --campbell``)."""

from .errors import ModelError


def parse_range(text, flag="--param"):
    """'NAME=START:STOP:COUNT' -> (name, (start, stop, count)); ModelError naming ``flag``
    where the text has another form."""
    name, sep, spec = text.partition("=")
    parts = spec.split(":")
    try:
        if not sep or len(parts) != 3:
            raise ValueError
        return name.strip(), (float(parts[0]), float(parts[1]), int(parts[2]))
    except ValueError:
        raise ModelError(f"{flag} {text!r}: expected NAME=START:STOP:COUNT, e.g. k1=10:100:20") from None
