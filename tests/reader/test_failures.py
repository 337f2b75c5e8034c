"""Every failure reason the reader's code can produce is a declared metric label, and vice versa."""

from __future__ import annotations

import re
from pathlib import Path

from gauged.reader.failures import failure_pairs

READER = Path(__file__).resolve().parents[2] / "gauged" / "reader"


def test_failure_pairs_cover_every_reason_in_the_reader_code():
    produced = set()
    for path in READER.glob("*.py"):
        text = path.read_text()
        stage = re.search(r'^STAGE = "(\w+)"', text, re.M)
        for match in re.finditer(r'StageFailure\(\s*(STAGE|"(\w+)"),\s*"(\w+)"', text):
            produced.add((match.group(2) or (stage.group(1) if stage else "?"), match.group(3)))
    declared = set(failure_pairs())
    assert produced - declared == set(), f"produced but not declared: {produced - declared}"


def test_failure_pairs_are_unique():
    pairs = failure_pairs()
    assert len(pairs) == len(set(pairs))
