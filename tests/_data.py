"""Where the real data shared with the project lives (scores and recordings, not in the repo).

``$ARCO_SHARED_DATA``, else ``<repo>/../shared/data``, else ``/work/shared/data``; a missing
directory fails the calling test with that message.
"""

from __future__ import annotations

from pathlib import Path

import pytest


def shared_data() -> Path:
    """The shared data directory (holding ``openscore-quartets/`` and ``bach-violin/``)."""
    from data_schemas.errors import ParameterError
    from pipelines.shared_data import shared_data_dir

    try:
        return shared_data_dir("openscore-quartets")
    except ParameterError as exc:
        pytest.fail(str(exc))
