"""``mbsynth modes MODEL``: natural frequencies, damping ratios and mode shapes (mbsynth.analysis.modes)."""

import html
import json
import tempfile
from pathlib import Path

import numpy as np

from ..analysis.modes import format_modes, mode_motion, modes, to_dict
from ..core.errors import ModelError
from ..core.files import write_atomically
from .outputs import Output
from .parsers import model_of

OUTPUTS = (Output("--html", (".html",)), Output("--plot", (".png", ".svg", ".pdf")))
ORDERS = 4  # --campbell's order lines 1P … 4P where --orders is not given


def run(args):
    system = model_of(args)
    if args.campbell is not None or args.plot is not None or args.orders is not None:
        return run_campbell(args, system)
    result = modes(system, equilibrium=args.equilibrium, steady=args.steady)
    if args.html:
        write_html(system, result, args.html)
    return report(args.json, to_dict(result), format_modes(result), args.html)


def run_campbell(args, system):
    """``--campbell NAME=START:STOP:COUNT`` (analysis/campbell.py): the table or JSON, and
    the ``--plot`` image."""
    from ..analysis.campbell import campbell, format_campbell, plot, to_dict
    from ..core.ranges import parse_range

    if args.campbell is None:
        given = "--plot" if args.plot is not None else "--orders"
        raise ModelError(f"{given} belongs to a Campbell diagram: give --campbell NAME=START:STOP:COUNT")
    if args.html or args.equilibrium:
        raise ModelError("--campbell sweeps steady motions: it takes neither --html nor --equilibrium")
    orders = ORDERS if args.orders is None else args.orders
    if orders < 1:
        raise ModelError(f"--orders must be a positive integer, got {orders}")
    name, (start, stop, count) = parse_range(args.campbell, "--campbell")
    if count < 2 or not stop > start:
        raise ModelError(f"--campbell {args.campbell}: an empty range; give START < STOP and COUNT ≥ 2")
    result = campbell(system, name, np.linspace(start, stop, count), orders)
    if args.plot:
        plot(result, args.plot)
    return report(args.json, to_dict(result), format_campbell(result), args.plot)


def report(as_json, record, text, written):
    """Print the result as JSON (``record``) or as ``text`` with the file ``written`` (if
    any) named after it; the exit status 0."""
    if as_json:
        print(json.dumps(record, indent=2))
    else:
        print(text)
        if written:
            print(f"wrote {written}")
    return 0


def write_html(system, result, path):
    """One HTML page: each mode's animation (viewer.to_html, self-contained) in a frame,
    chosen with a selector; written whole or not at all."""
    from ..view.viewer import to_html  # meshcat: only for --html
    pages = []
    with tempfile.TemporaryDirectory() as folder:
        for i, mode in enumerate(result.modes):
            page = to_html(system, mode_motion(system, result, i), Path(folder) / f"mode_{i}.html")
            label = f"mode {i + 1}: {mode.frequency:.4g} Hz, {mode.kind}"
            pages.append((label, page.read_text(encoding="utf-8")))
    options = "".join(f'<option value="{i}">{html.escape(label)}</option>' for i, (label, _) in enumerate(pages))
    frames = "".join(f'<iframe id="m{i}" srcdoc="{html.escape(text)}" style="display:{"block" if i == 0 else "none"}">'
                     "</iframe>" for i, (_, text) in enumerate(pages))
    document = (
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>modes of "
        f"{html.escape(result.system_name)}</title><style>iframe{{width:100%;height:90vh;border:0}}</style></head>"
        f"<body><label>mode <select id='mode' onchange=\"for (const f of document.querySelectorAll('iframe')) "
        "f.style.display = f.id === 'm' + this.value ? 'block' : 'none'\">"
        f"{options}</select></label>{frames}</body></html>")
    write_atomically(path, lambda temporary: temporary.write_text(document, encoding="utf-8"))
