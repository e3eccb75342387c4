"""The ensemble settings: seating (pans), room, master loudness and players' timing.

Shipped defaults live in ``pipelines/ensemble/ensemble.toml``; a user's TOML is merged over them
key by key and every value is checked (:class:`~data_schemas.errors.ParameterError`
naming the file and key).
"""

from __future__ import annotations

import math
import os
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

from data_schemas.errors import ParameterError

#: (section, key) -> (lowest, highest) of every number.
_RANGES = {
    ("seating", "max_itd"): (0.0, 0.002), ("room", "rt60"): (0.1, 10.0),
    ("room", "wet"): (0.0, 10.0), ("room", "seed"): (0, 2**63 - 1),
    ("master", "loudness"): (-70.0, 0.0), ("master", "ceiling"): (-40.0, 0.0),
    ("timing", "sigma"): (0.0, 0.05), ("timing", "limit"): (0.0, 0.1),
}
ROOMS = ("hall", "none")


def load_ensemble(path: str | os.PathLike | None = None) -> dict[str, Any]:
    """The shipped ensemble settings merged with the TOML at ``path`` (if any), checked.

    Examples
    --------
    >>> cfg = load_ensemble()
    >>> cfg["seating"]["pans"][0], cfg["room"]["rt60"], cfg["master"]["loudness"]
    (-0.7, 1.8, -18.0)
    """
    text = resources.files("pipelines").joinpath("ensemble/ensemble.toml").read_text("utf-8")
    config = tomllib.loads(text)
    if path is not None:
        path = Path(path)
        try:
            user = tomllib.loads(path.read_text("utf-8"))
        except (FileNotFoundError, IsADirectoryError):
            raise ParameterError(f"--mix-config {path}: file not found") from None
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise ParameterError(f"--mix-config {path}: not valid TOML ({exc})") from None
        _merge(config, user, str(path))
    check_ensemble(config, source=str(path or "pipelines/ensemble/ensemble.toml"))
    return config


def _merge(base: dict[str, Any], over: dict[str, Any], source: str) -> None:
    for section, values in over.items():
        if section not in base or not isinstance(values, dict):
            raise ParameterError(f"{source}: unknown section '{section}'")
        for key, value in values.items():
            if key not in base[section]:
                raise ParameterError(f"{source}: unknown setting '{section}.{key}'")
            base[section][key] = value


def check_ensemble(config: dict[str, Any], source: str = "ensemble settings") -> None:
    """Raise ParameterError unless every setting has its type and range.

    Examples
    --------
    >>> cfg = load_ensemble()
    >>> cfg["room"]["rt60"] = 0.0
    >>> check_ensemble(cfg, "x.toml")
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: x.toml: room.rt60 = 0.0 must lie in 0.1 .. 10.0
    """
    for (section, key), (low, high) in _RANGES.items():
        value = config[section][key]
        integral = isinstance(low, int)
        if isinstance(value, bool) or not isinstance(value, int | float) or (
                integral and not isinstance(value, int)) or not math.isfinite(value):
            raise ParameterError(f"{source}: {section}.{key} = {value!r} must be a number")
        if not low <= value <= high:
            raise ParameterError(f"{source}: {section}.{key} = {value} must lie in "
                                 f"{low} .. {high}")
    if config["room"]["kind"] not in ROOMS:
        raise ParameterError(f"{source}: room.kind = {config['room']['kind']!r} must be one "
                             f"of {', '.join(ROOMS)}")
    check_pans(config["seating"]["pans"], source)


def check_pans(pans: Any, source: str = "--pan") -> list[float]:
    """Pan positions as floats in [-1, 1] (ParameterError otherwise).

    Examples
    --------
    >>> check_pans([-1, 0.5])
    [-1.0, 0.5]
    """
    if not isinstance(pans, list) or not all(
            isinstance(p, int | float) and not isinstance(p, bool) and math.isfinite(p)
            and -1.0 <= p <= 1.0 for p in pans):
        raise ParameterError(f"{source}: pans = {pans!r} must be numbers in -1 .. 1")
    return [float(p) for p in pans]


def part_pans(config: dict[str, Any], n_parts: int) -> list[float]:
    """Pan position of each of ``n_parts`` parts in score order (centre beyond the list).

    Examples
    --------
    >>> part_pans(load_ensemble(), 5)
    [-0.7, -0.25, 0.25, 0.7, 0.0]
    """
    pans = check_pans(config["seating"]["pans"])
    return [pans[i] if i < len(pans) else 0.0 for i in range(n_parts)]
