"""The documentation site builds with `mkdocs build --strict` and no warning, and headless
Chromium opens its front page and API reference and finds their headings.

Needs the docs extra (`pip install ".[docs]"`), which `test` does not include: without it these
tests skip, saying so. .ci/run installs the extra after the main suite and runs this file again,
with Debian's chromium (installed as for tests/test_report.py)."""

from __future__ import annotations

import html
import importlib.util
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from conftest import CHECKOUT, headless_chromium

DOCS_EXTRA = ("mkdocs", "material", "mkdocstrings", "mkdocstrings_handlers.python")


def first_heading(page: str) -> str:
    """The text of a docs page's first `# ` heading (its title on the built page)."""
    text = (CHECKOUT / "docs" / page).read_text(encoding="utf-8")
    match = re.search(r"^#\s+(.*?)\s*$", text, re.M)
    assert match, f"docs/{page} has no # heading"
    return re.sub(r"[`*]", "", re.sub(r"\s*\{[^}]*\}\s*$", "", match.group(1)))


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site built from the checkout's mkdocs.yml into a temporary folder, and the
    build's log."""
    missing = [name for name in DOCS_EXTRA if importlib.util.find_spec(name.split(".")[0])
               is None or importlib.util.find_spec(name) is None]
    if missing:
        pytest.skip(f"the docs extra is not installed (no {', '.join(missing)}): "
                    f'python -m pip install ".[docs]"; .ci/run installs it and runs this file')
    out = tmp_path_factory.mktemp("site")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(out),
                           "-f", str(CHECKOUT / "mkdocs.yml")],
                          cwd=CHECKOUT, env=env, capture_output=True, text=True, timeout=600,
                          check=False)
    return out, done


def test_the_site_builds_strictly_without_a_warning(site):
    out, done = site
    log = done.stdout + done.stderr
    assert done.returncode == 0, f"mkdocs build --strict failed:\n{log[-4000:]}"
    warnings = [line for line in log.splitlines() if re.match(r"\W*(WARNING|ERROR)\b", line)]
    assert not warnings, "\n".join(warnings)
    assert (out / "index.html").is_file() and (out / "reference" / "index.html").is_file()
    reference = (out / "reference" / "index.html").read_text(encoding="utf-8")
    for name in ("occtrack.Tracker", "occtrack.TrackerConfig", "occtrack.Tracks",
                 "occtrack.TrackResult", "occtrack.OcctrackError"):
        assert f'id="{name}"' in reference, f"the API reference has no entry for {name}"


def headings(dom: str, level: int) -> list[str]:
    found = re.findall(rf"<h{level}\b[^>]*>(.*?)</h{level}>", dom, flags=re.S)
    return [" ".join(html.unescape(re.sub(r"<[^>]+>", " ", h)).replace("¶", "").split())
            for h in found]


@pytest.mark.parametrize(("page", "path"), [("index.md", "index.html"),
                                            ("reference.md", "reference/index.html")])
def test_chromium_finds_the_pages_headings(site, tmp_path, page, path):
    out, done = site
    assert done.returncode == 0, "the site did not build (see the strict build test)"
    url = (out / path).as_uri()
    dom = headless_chromium(tmp_path, "--dump-dom", url).stdout
    assert "<h1" in dom, f"Chromium drew no <h1> on {path}: {dom[:500]!r}"
    assert first_heading(page) in headings(dom, 1), (first_heading(page), headings(dom, 1))
    if page == "reference.md":
        entries = headings(dom, 2)
        for name in ("occtrack.Tracker", "occtrack.TrackerConfig", "occtrack.Tracks"):
            assert any(re.match(rf"{re.escape(name)}(?![\w.])", h) for h in entries), \
                (name, entries)
    shot = tmp_path / "page.png"
    headless_chromium(tmp_path, f"--screenshot={shot}", "--window-size=1200,800", url)
    assert shot.is_file(), f"Chromium wrote no screenshot of {path}"
    image = pytest.importorskip("PIL.Image", reason="reading the screenshot needs Pillow")
    with image.open(shot) as picture:
        pixels = np.asarray(picture.convert("L"), dtype=float)
    assert pixels.std() > 10, f"the screenshot of {path} is blank"
