"""Settings of the sample search: the shipped ``config/search.toml`` merged with the user's.

Weights of the target and continuity costs, the number of Viterbi candidates per note
(``n_best``), the continuity units and the fallback distances between note groups; see
:mod:`gesture_db.search` for how they enter the costs.
"""

from __future__ import annotations

import os
import tomllib
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

from data_schemas.errors import ParameterError

#: Bounds on the number of Viterbi candidates per note.
MAX_N_BEST = 1024


@lru_cache(maxsize=1)
def _default_text() -> str:
    return resources.files("gesture_db").joinpath("config/search.toml").read_text("utf-8")


def load_search_config(path: str | os.PathLike | None = None,
                       overrides: dict[str, Any] | None = None) -> dict[str, Any]:
    """The shipped search settings merged with a user TOML file and/or a dict, validated.

    Raises
    ------
    ParameterError
        Missing or unreadable file, unknown key, negative weight (naming file and key).
    """
    config = tomllib.loads(_default_text())
    if path is not None:
        p = Path(path)
        if not p.is_file():
            raise ParameterError(f"search config {p} not found")
        try:
            user = tomllib.loads(p.read_text("utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise ParameterError(f"search config {p}: not TOML ({exc})") from None
        _merge(config, user, str(p), "")
    if overrides:
        _merge(config, overrides, "<overrides>", "")
    _validate(config)
    return config


def _merge(base: dict, over: dict, source: str, prefix: str) -> None:
    for key, value in over.items():
        name = f"{prefix}{key}"
        open_table = prefix == "fallback.technique."
        if key not in base and not open_table:
            raise ParameterError(f"search config {source}: unknown key '{name}'")
        if isinstance(value, dict) and isinstance(base.get(key), dict):
            _merge(base[key], value, source, f"{name}.")
        else:
            base[key] = value


def _validate(config: dict) -> None:
    n = config["n_best"]
    if not isinstance(n, int) or not 1 <= n <= MAX_N_BEST:
        raise ParameterError(f"search config: n_best={n!r} must be an integer in 1..{MAX_N_BEST}")
    for section in ("weights", "continuity_scale"):
        for key, value in config[section].items():
            if not isinstance(value, int | float) or value < 0:
                raise ParameterError(f"search config: {section}.{key}={value!r} must be >= 0")
    for key, value in config["continuity_scale"].items():
        if value <= 0:
            raise ParameterError(f"search config: continuity_scale.{key}={value!r} must be > 0")
    if config["costs"]["dynamic_span"] <= 0:
        raise ParameterError("search config: costs.dynamic_span must be > 0")


__all__ = ["MAX_N_BEST", "load_search_config"]
