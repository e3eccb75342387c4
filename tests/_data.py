"""Where the real data shared with the project lives (scores and recordings, not in the repo).

``$ARCO_SHARED_DATA``, else ``<repo>/../shared/data``, else ``/work/shared/data``; a missing
directory fails the calling test with that message.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest


def shared_data() -> Path:
    """The shared data directory (holding ``openscore-quartets/`` and ``bach-violin/``)."""
    candidates = [os.environ.get("ARCO_SHARED_DATA"),
                  Path(__file__).resolve().parents[1].parent / "shared" / "data",
                  "/work/shared/data"]
    for c in candidates:
        if c and (Path(c) / "openscore-quartets").is_dir():
            return Path(c)
    pytest.fail("shared data not found: set ARCO_SHARED_DATA to the directory holding "
                f"openscore-quartets/ (tried {[str(c) for c in candidates if c]})")
