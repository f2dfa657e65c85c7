"""`occtrack report`: one static HTML page of a benchmark run, checked as text and in headless
Chromium, and the per-frame data and boxes `occtrack benchmark --json` keeps for it."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from conftest import headless_chromium
from occtrack.cli import main
from occtrack.experiments import benchmark
from occtrack.metrics.evaluate import gospa_per_frame
from sequences import write_sequence

TRACKERS = ("none", "measurement-wise")
LENGTH = 40


def make_sequence(folder, name: str, seed: int) -> None:
    """A synthetic MOTChallenge sequence folder: a crowd's ground truth and detections."""
    write_sequence(folder, name, people=8, frames=LENGTH, length=LENGTH, seed=seed)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """Two synthetic sequences, benchmarked with --keep-boxes, and the report page."""
    root = tmp_path_factory.mktemp("report")
    make_sequence(root / "data" / "SYN-A", "SYN-A", seed=4)
    make_sequence(root / "data" / "SYN-B", "SYN-B", seed=7)
    results = root / "run.json"
    assert main(["benchmark", str(root / "data"), "--trackers", ",".join(TRACKERS),
                 "--json", str(results), "--keep-boxes", "--quiet"]) == 0
    page = root / "report.html"
    assert main(["report", str(results), "-o", str(page), "--quiet"]) == 0
    return root, json.loads(results.read_text()), page.read_text(encoding="utf-8")


def test_per_frame_counts_are_the_protocols(run):
    """The kept GOSPA is `gospa_per_frame` under mot17 (its sum what occtrack eval reports),
    and the counts are the protocol's true objects and scored boxes."""
    root, report, _ = run
    for name in ("SYN-A", "SYN-B"):
        seq = benchmark.load_sequence(root / "data" / name)
        counts = report["sequences"][name]["per_frame"]
        boxes = report["sequences"][name]["boxes"]
        assert len(counts["truth"]) == LENGTH
        truth_frames = np.bincount(boxes["truth"]["frame"], minlength=LENGTH + 1)[1:]
        assert truth_frames.tolist() == counts["truth"]
        for tracker in TRACKERS:
            result = benchmark.track(tracker, seq)
            kept = counts["trackers"][tracker]
            expected = gospa_per_frame(seq.gt, result, "mot17", LENGTH)
            np.testing.assert_allclose(kept["gospa"], expected, atol=1e-6)
            # with c = 1 and p = 1 a missed or false object costs 1/2, a match its 1 - IoU
            lost = 0.5 * (np.array(kept["missed"]) + np.array(kept["false"]))
            assert np.all(np.array(kept["gospa"]) >= lost - 1e-9)
            matched = np.array(kept["estimates"]) - np.array(kept["false"])
            assert np.all(matched == np.array(counts["truth"]) - np.array(kept["missed"]))

            table = boxes["trackers"][tracker]
            assert len(table["frame"]) == len(result) == len(table["state"])
            assert table["frame"] == sorted(table["frame"])
            scored = np.ones(len(result), bool)
            scored[table["ignored"]] = False
            per_frame = np.bincount(np.array(table["frame"])[scored], minlength=LENGTH + 1)
            assert per_frame[1:].tolist() == kept["estimates"]
            assert set(table["state"]) <= {benchmark.DETECTED, benchmark.COASTING,
                                           benchmark.OCCLUDED}


def test_the_old_keys_are_kept_and_the_new_are_asked_for(run, tmp_path):
    root, kept, _ = run
    seq = root / "data" / "SYN-A"
    plain, frames = tmp_path / "plain.json", tmp_path / "frames.json"
    assert main(["benchmark", str(seq), "--trackers", "none", "--json", str(plain),
                 "--quiet"]) == 0
    assert main(["benchmark", str(seq), "--trackers", "none", "--json", str(frames),
                 "--per-frame", "--quiet"]) == 0
    plain, frames = json.loads(plain.read_text()), json.loads(frames.read_text())
    assert set(plain) == {"protocol", "trackers", "sequences", "combined", "mean"}
    entry = plain["sequences"]["SYN-A"]
    assert set(entry) == {"folder", "frames", "fps", "image_size", "trackers", "calibration"}
    assert set(frames["sequences"]["SYN-A"]) == set(entry) | {"per_frame"}
    assert set(kept["sequences"]["SYN-A"]) == set(entry) | {"per_frame", "boxes"}
    for report in (frames, kept):
        assert (set(report["sequences"]["SYN-A"]["trackers"]["none"])
                == set(entry["trackers"]["none"]))


def test_keeping_data_needs_a_json_file(run, capsys):
    root, _, _ = run
    assert main(["benchmark", str(root / "data" / "SYN-A"), "--trackers", "none",
                 "--keep-boxes"]) == 1
    assert "add --json FILE" in capsys.readouterr().err


def test_the_page_holds_every_table_and_fetches_nothing(run):
    _, report, page = run
    assert page.startswith("<!DOCTYPE html>")
    for forbidden in ("http://", "https://", "<link", "@import", "url(", " src=", "fetch("):
        assert forbidden not in page, forbidden
    tables = re.findall(r"<table.*?</table>", page, flags=re.S)
    assert len(tables) == 2 + 2  # combined, mean, one a sequence
    for name in ("SYN-A (1280x720, 10 fps, 40 frames)", "SYN-B (1280x720, 10 fps, 40 frames)",
                 "Combined over 2 sequences", "Mean over 2 sequences"):
        assert name in page
    for title in ("HOTA", "IDF1", "MOTA", "DetA", "AssA", "LocA", "FP", "FN", "IDSW", "ECE",
                  "frames/s"):
        assert f">{title}</th>" in page
    for values, table in [*((entry["trackers"], tables[2 + i])
                            for i, entry in enumerate(report["sequences"].values())),
                          (report["combined"]["trackers"], tables[0])]:
        for tracker in TRACKERS:
            row = re.search(rf"{re.escape(tracker)}</th>(.*?)</tr>", table).group(1)
            cells = re.findall(r"<td[^>]*>(.*?)</td>", row)
            scores = values[tracker]
            assert cells == [f"{scores['hota']:.3f}", f"{scores['idf1']:.3f}",
                             f"{scores['mota']:.3f}", f"{scores['deta']:.3f}",
                             f"{scores['assa']:.3f}", f"{scores['loca']:.3f}",
                             str(scores["fp"]), str(scores["fn"]),
                             str(scores["id_switches"]), f"{scores['ece']:.3f}",
                             f"{scores['frames_per_second']:.0f}"]
    assert page.count('<svg class="chart"') == 2 * 2 and page.count("<canvas") == 2
    assert page.count('<svg class="diagram"') == 1 + 2  # combined, one a sequence


def test_the_reliability_diagrams_are_the_reports_tables(run):
    """Each reliability diagram draws a dot per non-empty bin at (mean confidence, share
    right) of the JSON's table; the combined table pools the sequences' boxes bin by bin,
    and its ECE is the combined ECE column's."""
    _, report, page = run
    figures = re.findall(r'<svg class="diagram".*?</svg>', page, flags=re.S)
    entries = [report["combined"], *report["sequences"].values()]
    for figure, entry in zip(figures, entries, strict=True):
        for tracker in TRACKERS:
            table = entry["calibration"][tracker]
            group = re.search(rf'<g data-tracker="{re.escape(tracker)}">(.*?)</g>', figure,
                              flags=re.S).group(1)
            dots = re.findall(r"<title>[^:]*: (\d+) boxes, confidence ([\d.]+), right "
                              r"([\d.]+)</title>", group)
            expected = [(str(b), f"{c:.3f}", f"{r:.3f}") for b, c, r in
                        zip(table["boxes"], table["confidence"], table["right"], strict=True)
                        if b]
            assert dots == expected and dots
    for tracker in TRACKERS:
        parts = [s["calibration"][tracker] for s in report["sequences"].values()]
        pooled = report["combined"]["calibration"][tracker]
        boxes = np.sum([p["boxes"] for p in parts], axis=0)
        assert pooled["boxes"] == boxes.tolist()
        right = np.sum([np.nan_to_num(np.array(p["right"], float) * p["boxes"])
                        for p in parts], axis=0)
        share = np.array(pooled["right"], float)
        # each share is written to 6 decimals: a bin's count of right boxes is off by at most
        # half a millionth of its boxes, once in the pooled table and once over the parts
        assert (np.abs(share[boxes > 0] * boxes[boxes > 0] - right[boxes > 0])
                <= 1e-6 * boxes[boxes > 0]).all()
        assert pooled["ece"] == pytest.approx(report["combined"]["trackers"][tracker]["ece"])
    data = json.loads(re.search(r'<script type="application/json" id="occtrack-data">(.*?)'
                                r"</script>", page, flags=re.S).group(1))
    assert all(s["boxes"]["trackers"].keys() == set(TRACKERS) for s in data["sequences"])
    assert data["sequences"][0]["boxes"] == report["sequences"]["SYN-A"]["boxes"]


def test_without_per_frame_data_the_page_says_how(run, tmp_path, capsys):
    root, _, _ = run
    results, page = tmp_path / "plain.json", tmp_path / "plain.html"
    assert main(["benchmark", str(root / "data"), "--trackers", "none", "--json",
                 str(results), "--quiet"]) == 0
    assert main(["report", str(results), "-o", str(page)]) == 0
    assert "--keep-boxes" in capsys.readouterr().out
    text = page.read_text()
    assert "<canvas" not in text and '<svg class="chart"' not in text
    assert text.count("<table") == 4 and "--keep-boxes" in text


def test_bad_input_and_outputs_are_named(run, tmp_path, capsys):
    root, _, _ = run
    results = root / "run.json"
    out = tmp_path / "page.html"
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["report", str(bad), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert str(bad) in err and "invalid JSON" in err and "occtrack benchmark" in err
    bad.write_text('{"protocol": "mot17"}')
    assert main(["report", str(bad), "-o", str(out)]) == 1
    assert "no 'trackers' key" in capsys.readouterr().err
    assert main(["report", str(tmp_path / "absent.json"), "-o", str(out)]) == 1
    assert "absent.json" in capsys.readouterr().err
    broken = json.loads(results.read_text())
    broken["sequences"]["SYN-B"]["calibration"]["none"]["right"].pop()
    bad.write_text(json.dumps(broken))
    assert main(["report", str(bad), "-o", str(out)]) == 1
    assert ("sequence 'SYN-B': the calibration of 'none' is not equal lists boxes, "
            "confidence, right") in capsys.readouterr().err
    assert main(["report", str(results), "-o", str(results), "--force"]) == 1
    assert "is also an input" in capsys.readouterr().err
    out.write_text("keep me")
    assert main(["report", str(results), "-o", str(out)]) == 1
    assert "exists already" in capsys.readouterr().err and out.read_text() == "keep me"
    assert main(["report", str(results), "-o", str(out), "--force", "--show", "deepsort"]) == 1
    assert "no tracker 'deepsort' in this report" in capsys.readouterr().err
    assert main(["report", str(results), "-o", str(out), "--force", "--quiet",
                 "--show", "measurement-wise"]) == 0
    page = out.read_text()
    assert page.startswith("<!DOCTYPE html>")
    assert page.count('<option value="measurement-wise" selected>') == 2
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_the_page_in_headless_chromium(run, tmp_path):
    """Chromium draws the page (a screenshot that is not blank) and its DOM, after the script
    has run, holds the tables and a drawn frame viewer."""
    root, report, _ = run
    url = (root / "report.html").as_uri()
    shot = tmp_path / "report.png"
    done = headless_chromium(tmp_path, f"--screenshot={shot}", "--window-size=1280,2000", url)
    assert shot.is_file(), done.stderr[-2000:]
    image = pytest.importorskip("PIL.Image", reason="reading the screenshot needs Pillow")
    with image.open(shot) as picture:
        assert picture.size == (1280, 2000)
        pixels = np.asarray(picture.convert("L"), dtype=float)
    assert pixels.std() > 10, "the screenshot is blank"
    assert len(np.unique(pixels)) > 50

    dom = headless_chromium(tmp_path, "--dump-dom", url).stdout
    assert 'data-ready="yes"' in dom, "the page's script did not run to its end"
    assert "Combined over 2 sequences" in dom and "SYN-B (1280x720, 10 fps, 40 frames)" in dom
    hota = report["combined"]["trackers"]["measurement-wise"]["hota"]
    assert f"{hota:.3f}" in dom
    drawn = [int(n) for n in re.findall(r'<canvas [^>]*data-drawn="(\d+)"', dom)]
    assert len(drawn) == 2 and all(n > 0 for n in drawn)
    assert re.search(r'class="info">frame \d+: \d+ true objects; none \d+ boxes scored', dom)
