"""The demo's printed scores are the README's. (That it repeats byte for byte by seed, in
fresh processes, is tests/test_determinism.py's.)"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

pytest.importorskip("motmetrics", reason="the demo scores with the eval extra")

from occtrack.cli import main  # noqa: E402

README = Path(__file__).resolve().parents[1] / "README.md"


def readme_rows() -> dict[str, list[str]]:
    """The rows of the README's `$ occtrack demo` transcript, by occlusion model."""
    text = README.read_text(encoding="utf-8")
    block = text[text.index("$ occtrack demo\n"):]
    block = block[:block.index("```")]
    rows = {}
    for line in block.splitlines():
        m = re.match(r"(none|object-wise|measurement-wise)\s+(.*)", line)
        if m:
            rows[m[1]] = m[2].split()
    return rows


def demo_json(capsys) -> dict:
    assert main(["demo", "--json", "--quiet"]) == 0
    return json.loads(capsys.readouterr().out)


def test_demo_prints_the_readme_scores(capsys):
    first = demo_json(capsys)
    rows = readme_rows()
    assert sorted(rows) == ["measurement-wise", "none", "object-wise"]
    for name, printed in rows.items():
        got = first["trackers"][name]
        assert printed[:5] == [f"{got['mota']:.3f}", f"{got['idf1']:.3f}",
                               str(got["id_switches"]), f"{got['gospa_per_frame']:.3f}",
                               str(got["tracks"])], name
    detector = first["detector"]
    assert (f"detector: recall {detector['recall']:.3f}, precision "
            f"{detector['precision']:.3f}\n") in README.read_text(encoding="utf-8")
