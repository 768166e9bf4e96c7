"""RollBall's data files: the example scenes (``examples/*.json``), the app's icon (``icons/``)
and help pages (``help_pages/``).

This folder is installed as the package ``rollball.resources`` (``pyproject.toml`` maps it), so
its files are found with ``importlib.resources`` from any folder, in a checkout (editable
install) as in an installed wheel. This module is the one place that knows where they are: the
core and the app ask :func:`path`.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path


def path(*parts: str) -> Path:
    """The shipped file or folder at ``parts`` below this package, e.g. ``path("icons",
    "rollball.svg")``. An installed package is a folder on disk, so this is a ``Path``."""
    return Path(str(resources.files(__name__).joinpath(*parts)))
