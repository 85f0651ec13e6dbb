"""The benchmarks' common ending: print the report as JSON and, with ``--out``, write the same text to a file; and
the common start, :func:`run_main`, which turns bad input into one line instead of a traceback."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path


def emit(report: dict, out: Path | None) -> None:
    text = json.dumps(report, indent=1)
    print(text)
    if out:
        Path(out).write_text(text + "\n")


def run_main(main: Callable[[], int | None]) -> None:
    """Run a benchmark's ``main`` and exit with its return value. Bad input raises :class:`CenterArtError` with a
    message that names the file or argument (a missing checkpoint or scenes folder, a folder that is not an
    evaluation's output): that message ends the run as one line on stderr with exit status 2, as the CLI does,
    instead of a traceback from deep inside the package."""
    from centerart.errors import CenterArtError

    try:
        status = main()
    except CenterArtError as err:
        print(f"error: {err}", file=sys.stderr)
        raise SystemExit(2) from None
    raise SystemExit(status)
