"""One word per concept: the package, the docs and the model files use part, constraint,
balance, projection and "the compiled path", never the retired words for them. A retired
word may appear only on a line that calls it an old name (where it is still read)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RETIRED = {  # pattern -> the word to use
    r"\bsubsystems?\b": "part",
    r"\bconnectors?\b": "constraint",
    r"(?<!loop )\bclosures?\b": "balance (balances: auto)",
    r"\bfast[- ]paths?\b|\bkernel path\b": "the compiled path",
    r"\bMBSYNTH_FAST\b": "MBSYNTH_COMPILED",
}
OLD_NAME = "old name"  # a line that says this may name the old word it reads


def scanned():
    yield from sorted((ROOT / "mbsynth").rglob("*.py"))
    yield from sorted((ROOT / "docs").rglob("*.md"))
    yield from sorted((ROOT / "models").rglob("*.yaml"))


def test_the_retired_words_are_used_nowhere():
    found = []
    for path in scanned():
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if OLD_NAME in line:
                continue
            for pattern, word in RETIRED.items():
                for match in re.finditer(pattern, line, re.IGNORECASE):
                    found.append(f"{path.relative_to(ROOT)}:{number}: '{match.group()}' (say {word})")
    assert not found, "\n".join(found)


def test_the_scan_finds_a_retired_word():
    line = "a massless subsystem's closure, on the fast path"
    hits = [p for p in RETIRED if re.search(p, line, re.IGNORECASE)]
    assert len(hits) == 3 and not any(re.search(p, "the loop closure of a four-bar", re.I) for p in RETIRED)
