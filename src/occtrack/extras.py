"""Which optional extra brings which library, so that a missing one is named with its install
command (the core install is the tracker alone: numpy, scipy, tqdm).

    pip install "occtrack[eval]"          TrackEval and motmetrics: occtrack eval, demo, benchmark
    pip install "occtrack[viz]"           matplotlib, Pillow, imageio, PyAV: figures, render
    pip install "occtrack[supervision]"   occtrack.integrations.supervision
    pip install "occtrack[peers]"         Roboflow's trackers: the peers in occtrack benchmark
    pip install "occtrack[all]"           all of them
"""

from __future__ import annotations

import importlib
from types import ModuleType

from occtrack.errors import OcctrackError

EXTRA_OF = {
    "trackeval": "eval", "motmetrics": "eval", "pandas": "eval", "pycocotools": "eval",
    "tabulate": "eval", "cv2": "eval", "xmltodict": "eval",
    "matplotlib": "viz", "PIL": "viz", "imageio": "viz", "av": "viz",
    "supervision": "supervision",
    "trackers": "peers",
}


def install_command(extra: str) -> str:
    return f'pip install "occtrack[{extra}]"'


def missing_extra(err: BaseException) -> str | None:
    """The extra that brings the module an ImportError is about, or None."""
    if not isinstance(err, ImportError) or not err.name:
        return None
    return EXTRA_OF.get(err.name.split(".")[0])


def explain_missing(err: BaseException, what: str = "this") -> str | None:
    """One line naming the missing library and the extra to install, or None."""
    extra = missing_extra(err)
    if extra is None:
        return None
    module = err.name.split(".")[0]  # type: ignore[union-attr]
    return (f"{what} needs {module}, from the optional {extra!r} extra: install it with "
            f"{install_command(extra)}")


def require(module: str, what: str) -> ModuleType:
    """Import `module` or raise OcctrackError saying which extra brings it."""
    try:
        return importlib.import_module(module)
    except ImportError as err:
        message = explain_missing(err, what)
        if message is None:
            raise
        raise OcctrackError(message) from None
