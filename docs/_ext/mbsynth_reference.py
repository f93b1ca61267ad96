"""Sphinx extension: the model-file and CLI reference pages, generated at build time.

``model_files_page()`` writes the loader's schema (mbsynth.io.part_types.SECTIONS) as MyST
markdown, ``cli_page()`` the ``mbsynth`` argparse parsers (mbsynth.cli.parsers.parser);
``setup`` writes both into the source folder (``model-files.md``, ``cli.md``, not kept in
git) when the build starts, so neither page can drift from the code.
"""

import argparse
import re
from pathlib import Path

from mbsynth.cli.parsers import EXIT_CODES, VERDICTS, parser
from mbsynth.io.part_types import SECTIONS

_CODE = re.compile(r"(``.*?``|`[^`]*`)")


def _escape(text, cell=False):
    """Markdown text from plain text: punctuation markdown would read is escaped outside
    code spans (and ``|`` inside a table cell)."""
    parts = _CODE.split(text)
    special = r"[\\*_<>\[\]|#]" if not cell else r"[\\<>\[\]|]"
    parts = [p if i % 2 else re.sub(special, lambda m: "\\" + m.group(), p) for i, p in enumerate(parts)]
    return "".join(parts)


def _links(text):
    """``*name*`` of a schema section becomes a link to it."""
    return re.sub(r"\*([a-z_]+)\*", lambda m: f"{{ref}}`{m.group(1)} <model-{m.group(1)}>`"
                  if m.group(1) in SECTIONS else m.group(), text)


def model_files_page():
    """The model-file reference: one section per kind of mapping, one row per key."""
    lines = ["# Model files", "",
             "Every key a model file (YAML) may hold, generated from `mbsynth/io/schema.py`: the same "
             "tables the loader checks files against, so a key listed here is accepted and any other "
             "is refused with a `ModelError` naming the file and line. Expressions are parsed by "
             "`mbsynth.core.expressions` (never evaluated as code); an *expression of parameters* may use "
             "the model's `parameters` and the constants `pi`, `e`.", ""]
    for section in SECTIONS.values():
        lines += [f"(model-{section.name})=", f"## `{section.name}`", "", f"*Where:* {section.where}", ""]
        if section.text:
            lines += [_links(_escape(section.text, cell=True)), ""]
        lines += ["| key | type | default | meaning | example |", "|---|---|---|---|---|"]
        for key in section.keys:
            default = "**required**" if key.required else _escape(key.default or "—", cell=True)
            cells = (f"`{key.name}`", _links(_escape(key.type, cell=True)), default,
                     _links(_escape(key.meaning, cell=True)), f"`{key.example}`".replace("|", "\\|"))
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def _subcommands(top):
    """(name, parser, help) of each ``mbsynth`` command, in the parser's order."""
    action = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    helps = {choice.dest: choice.help for choice in action._choices_actions}
    return [(name, sub, helps.get(name, "")) for name, sub in action.choices.items()]


def _argument(sub, action):
    """One bullet: the flag or positional with its value name, its help and default."""
    formatter = sub._get_formatter()
    if action.option_strings:
        value = "" if action.nargs == 0 else " " + formatter._format_args(action, action.dest.upper())
        name = ", ".join(action.option_strings) + value
    else:
        name = formatter._format_args(action, action.metavar or action.dest)
    text = _escape(formatter._expand_help(action)) if action.help else ""
    extras = []
    if action.required and action.option_strings:
        extras.append("required")
    if action.choices is not None and not all(str(c) in text for c in action.choices):
        extras.append("one of " + ", ".join(f"`{c}`" for c in action.choices))
    suffix = f" ({'; '.join(extras)})" if extras else ""
    return f"- `{name}` — {text}{suffix}"


def cli_page():
    """The CLI reference: every command, its usage, description and every flag."""
    top = parser()
    lines = ["# Command line", "",
             "Generated from the argparse parsers of `mbsynth.cli.parsers`. Every command has `--help`; "
             "`--json` prints one JSON object on stdout (on an error `{\"error\": ...}`, else one line "
             "`error: ...` on stderr).", "",
             "```text", top.format_usage().strip(), "```", "",
             "(cli-exit-status)=", "## Exit status", "",
             "Every command exits with one of these (`mbsynth.cli.parsers.EXIT_CODES`; each command's "
             "`--help` ends with its own line of it):", "",
             "| status | meaning |", "|---|---|"]
    lines += [f"| {code} | {_escape(meaning, cell=True)} |" for code, meaning in EXIT_CODES.items()]
    lines += ["", "What a verdict (exit 1) is, command by command:", "",
              "| command | exit 1 |", "|---|---|"]
    lines += [f"| `{name}` | {_escape(verdict or 'never: it has no verdict', cell=True)} |"
              for name, verdict in VERDICTS.items()]
    lines.append("")
    for name, sub, help_ in _subcommands(top):
        lines += [f"(cli-{name})=", f"## `mbsynth {name}`", "", _escape(help_[:1].upper() + help_[1:]) + ".", "",
                  "```text", sub.format_usage().strip(), "```", "", _escape(sub.description or ""), ""]
        lines += [_argument(sub, a) for a in sub._actions
                  if a.help != argparse.SUPPRESS and not isinstance(a, argparse._HelpAction)]
        lines += ["", _escape(sub.epilog or ""), ""]
    return "\n".join(lines)


PAGES = {"model-files.md": model_files_page, "cli.md": cli_page}


def write_pages(app):
    """Write the generated pages into the source folder (only when their text changed,
    so that an unchanged page is not rebuilt)."""
    for name, make in PAGES.items():
        path = Path(app.srcdir) / name
        text = make()
        if not path.exists() or path.read_text() != text:
            path.write_text(text)


def setup(app):
    app.connect("builder-inited", write_pages)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
