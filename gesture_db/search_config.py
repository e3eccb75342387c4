"""Settings of the sample search: the shipped ``config/search.toml`` merged with the user's.

Weights of the target and continuity costs, the number of Viterbi candidates per note
(``n_best``), the continuity units and the fallback distances between note groups; see
:mod:`gesture_db.search` for how they enter the costs.
"""

from __future__ import annotations

import math
import os
import tomllib
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

from data_schemas.errors import ParameterError
from data_schemas.instruments import check_beta_range, check_instrument_names

#: Bounds on the number of Viterbi candidates per note.
MAX_N_BEST = 1024
#: Largest weight, scale or distance accepted (a sane bound, far above any useful value).
MAX_VALUE = 1e6
#: Settings that are lists of instrument names, not numbers.
NAME_LISTS = ("render.bite", "render.limit_acceleration", "render.pressing_limit")
#: Tables of beta ranges per instrument (``[low, high]``), not numbers.
RANGE_TABLES = ("render.beta_range",)


@lru_cache(maxsize=1)
def _default_text() -> str:
    return resources.files("gesture_db").joinpath("config/search.toml").read_text("utf-8")


def load_search_config(path: str | os.PathLike | None = None,
                       overrides: dict[str, Any] | None = None) -> dict[str, Any]:
    """The shipped search settings merged with a user TOML file and/or a dict, validated.

    Raises
    ------
    ParameterError
        Missing or unreadable file, unknown key, a value that is not a finite number in
        0..:data:`MAX_VALUE` (naming file and key).

    Examples
    --------
    >>> load_search_config(overrides={"weights": {"gesture": 2.0}})["weights"]["gesture"]
    2.0
    >>> load_search_config(overrides={"weights": {"gesture": float("nan")}})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: search config <overrides>: weights.gesture=nan must be ...
    """
    config = tomllib.loads(_default_text())
    sources = []
    if path is not None:
        p = Path(path)
        if not p.is_file():
            raise ParameterError(f"search config {p} not found")
        try:
            user = tomllib.loads(p.read_text("utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise ParameterError(f"search config {p}: not TOML ({exc})") from None
        _merge(config, user, str(p), "")
        sources.append(str(p))
    if overrides:
        _merge(config, overrides, "<overrides>", "")
        sources.append("<overrides>")
    _validate(config, f"search config {' + '.join(sources)}" if sources else "search config")
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


def _validate(config: dict, where: str) -> None:
    n = config["n_best"]
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_N_BEST:
        raise ParameterError(f"{where}: n_best={n!r} must be an integer in 1..{MAX_N_BEST}")
    for name, value in _numbers(config, ""):
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(
                value):
            raise ParameterError(f"{where}: {name}={value!r} must be a finite number")
        if value < 0:
            raise ParameterError(f"{where}: {name}={value!r} must be >= 0")
        if value > MAX_VALUE:
            raise ParameterError(f"{where}: {name}={value!r} must be <= {MAX_VALUE:g}")
    for key, value in config["continuity_scale"].items():
        if value <= 0:
            raise ParameterError(f"{where}: continuity_scale.{key}={value!r} must be > 0")
    if config["costs"]["dynamic_span"] <= 0:
        raise ParameterError(f"{where}: costs.dynamic_span must be > 0")
    for key in NAME_LISTS:
        check_instrument_names(config["render"][key.split(".", 1)[1]], key, where)
    for key in RANGE_TABLES:
        for name, value in config["render"][key.split(".", 1)[1]].items():
            check_beta_range(value, f"{key}.{name}", where)


def _numbers(table: dict, prefix: str):
    """``(dotted name, value)`` of every numeric setting below the top level."""
    for key, value in table.items():
        if isinstance(value, dict):
            if f"{prefix}{key}" not in RANGE_TABLES:
                yield from _numbers(value, f"{prefix}{key}.")
        elif prefix and f"{prefix}{key}" not in NAME_LISTS:
            yield f"{prefix}{key}", value


__all__ = ["MAX_N_BEST", "MAX_VALUE", "NAME_LISTS", "RANGE_TABLES", "load_search_config"]
