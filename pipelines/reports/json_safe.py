"""JSON-safe copies of figures: NaN/inf -> None, numpy scalars -> Python, paths -> text.

Examples
--------
>>> import numpy as np
>>> json_safe({"a": np.float64("nan"), "b": [np.int64(2), 1.23456]}, digits=4)
{'a': None, 'b': [2, 1.2346]}
>>> json_safe({"x": float("inf"), "y": 0.123456789})
{'x': None, 'y': 0.123456789}
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np


def json_safe(value: Any, digits: int | None = None) -> Any:
    """A JSON-safe copy of ``value`` (nested dicts, lists and tuples).

    Non-finite floats become None, floats are rounded to ``digits`` decimals (None: kept),
    numpy booleans and integers become Python ones, keys and paths become text.
    """
    if isinstance(value, Mapping):
        return {str(k): json_safe(v, digits) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v, digits) for v in value]
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        if not math.isfinite(value):
            return None
        return float(value) if digits is None else round(float(value), digits)
    if isinstance(value, Path):
        return str(value)
    return value


__all__ = ["json_safe"]
