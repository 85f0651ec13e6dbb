"""User-facing errors.

Every problem caused by the user's input (a malformed URDF, a missing mesh, a wrong image size) is raised as
:class:`CenterArtError` with a message that names the file and the problem. The CLI prints that message and
exits with status 2 instead of showing a traceback from deep inside a library.
"""

from __future__ import annotations

from pathlib import Path


class CenterArtError(Exception):
    """An error in the user's input or configuration, with a message meant for a person."""


class AssetError(CenterArtError):
    """An articulated-object folder cannot be used (bad URDF, missing mesh, joint without limits, ...)."""

    def __init__(self, path: str | Path, problem: str):
        self.path = Path(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")
