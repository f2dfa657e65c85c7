"""Pictures are written whole or not at all, like every other output (`occtrack.io.atomic`)."""

from __future__ import annotations

import os

from occtrack.errors import OcctrackError
from occtrack.io.atomic import atomic_path


def save(fig, path: str | os.PathLike, overwrite: bool = False, **savefig) -> None:
    """Save a matplotlib figure through a temporary file renamed into place, and close it
    whatever happens (an open figure per failed call would pile up in a long session)."""
    import matplotlib.pyplot as plt

    try:
        with atomic_path(path, overwrite) as tmp:
            fig.savefig(tmp, **savefig)
    except ValueError as err:
        raise OcctrackError(f"cannot draw this picture: {err}", str(path)) from None
    finally:
        plt.close(fig)


def save_animation(anim, fig, path: str | os.PathLike, overwrite: bool = False,
                   **save) -> None:
    """`save` for a matplotlib animation."""
    import matplotlib.pyplot as plt

    try:
        with atomic_path(path, overwrite) as tmp:
            anim.save(tmp, **save)
    finally:
        plt.close(fig)
