"""Where the real data shared with the project lives (scores and recordings, not in the repo).

Looked for, in order: ``$ARCO_SHARED_DATA``; ``../shared/data`` beside the repository;
``/work/shared/data`` (where this project's machines keep it). The first one holding the
folder asked for wins.

Examples
--------
>>> [p.name for p in candidates()][-1]
'data'
"""

from __future__ import annotations

import os
from pathlib import Path

from data_schemas.errors import ParameterError

#: Environment variable naming the shared data folder.
ENV = "ARCO_SHARED_DATA"
_REPO = Path(__file__).resolve().parents[1]


def candidates() -> list[Path]:
    """The places searched, in order."""
    env = os.environ.get(ENV)
    return [*([Path(env)] if env else []), _REPO.parent / "shared" / "data",
            Path("/work/shared/data")]


def shared_data_dir(holding: str = "openscore-quartets") -> Path:
    """The first shared data folder that holds ``holding`` (a sub-folder name).

    Raises
    ------
    ParameterError
        None of :func:`candidates` holds it (the message names every place tried).
    """
    tried = candidates()
    for c in tried:
        if (c / holding).is_dir():
            return c
    raise ParameterError(f"shared data not found: no {holding}/ in "
                         f"{' or '.join(str(c) for c in tried)} (set {ENV} to the folder "
                         f"holding {holding}/)")


__all__ = ["ENV", "candidates", "shared_data_dir"]
