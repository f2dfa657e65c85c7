"""Where the tests find MOT17, and what a test does when its data is missing.

Data-dependent tests look where the commands look: `OCCTRACK_DATA`, else `../shared/data/mot17`
beside this checkout (never an absolute path). Without the data a test skips on a developer's
machine, but fails in CI (`CI=true`): a CI run that quietly tested nothing must not pass.
Tests of optional extras (norfair's environment, `pytest.importorskip`) still skip, with a
reason, everywhere.

`OCCTRACK_HYPOTHESIS_PROFILE=mutation` (set by benchmarks/mutation.py) turns hypothesis's
shrinking off: a planted fault fails a property test at once, and shrinking the failing example
could take minutes, past mutmut's timeout."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from occtrack.errors import OcctrackError
from occtrack.io.data import SEQUENCE, find_sequence

CHECKOUT = Path(__file__).resolve().parents[1]

try:
    from hypothesis import Phase, settings
except ImportError:  # the test extra is not installed: the property tests skip
    pass
else:
    settings.register_profile("mutation", phases=[Phase.explicit, Phase.reuse, Phase.generate])
    settings.load_profile(os.environ.get("OCCTRACK_HYPOTHESIS_PROFILE", "default"))


def in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() in ("1", "true", "yes")


def data_missing(reason: str) -> None:
    """Skip the calling test, or fail it in CI."""
    if in_ci():
        pytest.fail(f"{reason}\n(CI=true: a test that needs data must find it in CI)",
                    pytrace=False)
    pytest.skip(reason)


def mot17_root() -> tuple[Path, str]:
    """The folder searched for MOT17 sequences, and where that choice came from."""
    if os.environ.get("OCCTRACK_DATA"):
        return Path(os.environ["OCCTRACK_DATA"]), "OCCTRACK_DATA"
    return CHECKOUT.parent / "shared" / "data" / "mot17", "../shared/data/mot17 of the checkout"


@pytest.fixture(scope="session")
def mot17_04() -> Path:
    """The MOT17-04 sequence folder (gt/gt.txt, seqinfo.ini); skip, or fail in CI, without it."""
    root, origin = mot17_root()
    try:
        return find_sequence(root, SEQUENCE)
    except OcctrackError:
        pass
    data_missing(f"MOT17 data not found: no {SEQUENCE}/gt/gt.txt and seqinfo.ini in {root} "
                 f"({origin}); set OCCTRACK_DATA to the folder that holds the sequence folders")


@pytest.fixture(scope="session")
def mot17_04_gt(mot17_04) -> Path:
    return mot17_04 / "gt" / "gt.txt"


@pytest.fixture(scope="session")
def kitti_root() -> Path:
    """The KITTI tracking folder (label_02/, det_02/rrc/, det_02/pointrcnn/, seqinfo/): beside
    the checkout (../shared/data/kitti), else beside the MOT17 folder OCCTRACK_DATA names (the
    data folder's kitti/, where .ci/run finds MOT17); skip, or fail in CI, without it."""
    tried = [CHECKOUT.parent / "shared" / "data" / "kitti"]
    if os.environ.get("OCCTRACK_DATA"):
        tried.append(Path(os.environ["OCCTRACK_DATA"]).parent / "kitti")
    for root in tried:
        if (root / "det_02").is_dir() and (root / "seqinfo").is_dir():
            return root
    data_missing("KITTI tracking data not found: no det_02/ and seqinfo/ in "
                 + " or ".join(str(root) for root in tried)
                 + " (../shared/data/kitti of the checkout, or kitti/ beside OCCTRACK_DATA)")


@pytest.fixture(scope="session")
def laser_recording() -> Path:
    """The leg-tracker benchmark's recording folder (person_following_outdoor_1/: the bag,
    scans.csv, the annotation): beside the checkout (../shared/data/laser), else beside the
    MOT17 folder OCCTRACK_DATA names; skip, or fail in CI, without it."""
    tried = [CHECKOUT.parent / "shared" / "data" / "laser"]
    if os.environ.get("OCCTRACK_DATA"):
        tried.append(Path(os.environ["OCCTRACK_DATA"]).parent / "laser")
    for root in tried:
        if (root / "person_following_outdoor_1").is_dir():
            return root / "person_following_outdoor_1"
    data_missing("the leg-tracker recording not found: no person_following_outdoor_1/ in "
                 + " or ".join(str(root) for root in tried)
                 + " (../shared/data/laser of the checkout, or laser/ beside OCCTRACK_DATA)")


def headless_chromium(tmp_path, *args: str):
    """Debian's chromium run headless on `args` with a fresh profile in `tmp_path` (the
    report page's test and the docs site's); skips, saying how to get it, where it is absent."""
    import shutil
    import subprocess

    browser = shutil.which("chromium")
    if browser is None:
        pytest.skip("no browser: Debian's chromium is not installed (apt-get install -y "
                    "chromium; .ci/run installs it where apt-get can)")
    profile = tmp_path / f"profile-{len(list(tmp_path.iterdir()))}"
    profile.mkdir()
    return subprocess.run(
        [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
         "--no-first-run", "--disable-background-networking", "--disable-component-update",
         "--disable-sync", f"--user-data-dir={profile}", *args],
        capture_output=True, text=True, timeout=180, check=False)
