"""The listening loop's settings from TOML: the control law and the teacher's thresholds.

``synth/listening/config/listening.toml`` holds the defaults (equal to those of
:class:`~synth.listening.controller.ControllerSettings` and
:class:`~synth.listening.teacher.TeacherThresholds`) with their provenance; a file of one's
own may set any of its keys. :func:`load_listening_settings` validates every key: an
unknown section or key, a wrong type or a value out of range is a
:class:`~data_schemas.errors.SchemaError` naming the file and the key.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, fields, replace
from importlib import resources
from pathlib import Path

from data_schemas.errors import SchemaError
from synth.listening.controller_settings import ControllerSettings
from synth.listening.teacher import TeacherThresholds

#: Valid range of each key: (type, lowest, highest), both ends included.
RANGES: dict[str, dict[str, tuple[type, float, float]]] = {
    "controller": {
        "average": (int, 1, 1000),
        "min_speed_share": (float, 0.0, 1.0),
        "jitter": (float, 0.0, 0.5),
        "range_margin": (float, 0.0, 100.0),
        "grace_hops": (int, 0, 100000),
        "step": (float, 1.0, 10.0),
        "good_share": (float, 0.0, 1.0),
        "change_hops": (int, 0, 100000),
        "trim": (float, 0.0, 100.0),
        "trim_up": (float, 0.0, 100.0),
        "sure": (float, 0.0, 1.0),
        "practised_start": (bool, 0.0, 1.0),
        "periodic_gate": (float, 0.0, 1.0),
        "ease_crossings": (float, 0.0, 1000.0),
        "ease_after": (int, 1, 100000),
        "ease_factor": (float, 0.0, 1.0),
        "ease_hops": (int, 1, 100000),
    },
    "teacher": {
        "silent_db": (float, -200.0, 0.0),
        "helmholtz_share": (float, 0.0, 1.0),
        "slips_tolerance": (float, 0.0, 1.0),
        "pitch_ok_cents": (float, 0.0, 1200.0),
        "flat_cents": (float, 0.0, 1200.0),
        "wrong_pitch_cents": (float, 0.0, 1200.0),
        "raucous_acf": (float, 0.0, 1.0),
        "noise_acf": (float, 0.0, 1.0),
        "alf_margin": (float, 0.0, 1.0),
        "multiple_slips": (float, 1.0, 100.0),
        "periodic_acf": (float, 0.0, 1.0),
    },
}


@dataclass(frozen=True)
class ListeningSettings:
    """The control law's tuning and the teacher's thresholds, read together."""

    controller: ControllerSettings
    teacher: TeacherThresholds


def default_settings_path() -> Path:
    """The shipped ``listening.toml`` (the defaults and their provenance)."""
    return Path(str(resources.files("synth.listening") / "config" / "listening.toml"))


def _value(raw: object, kind: type, lo: float, hi: float, key: str,
           source: str) -> float | bool:
    """``raw`` checked against the key's type and range (a bool key: true or false)."""
    if kind is bool:
        if not isinstance(raw, bool):
            raise SchemaError(f"{key} = {raw!r} must be true or false", source=source)
        return raw
    ok_type = not isinstance(raw, bool) and (
        isinstance(raw, int) if kind is int else isinstance(raw, int | float))
    if not ok_type:
        raise SchemaError(f"{key} = {raw!r} must be {'an integer' if kind is int else 'a number'}",
                          source=source)
    if not (math.isfinite(raw) and lo <= raw <= hi):
        raise SchemaError(f"{key} = {raw!r} is outside {lo:g}..{hi:g}", source=source)
    return kind(raw)


def load_listening_settings(path: str | os.PathLike | None = None) -> ListeningSettings:
    """Read and validate a listening settings file (default: the shipped defaults).

    Parameters
    ----------
    path : path-like, optional
        A TOML file with ``[controller]`` and/or ``[teacher]`` tables; missing keys keep
        their defaults.

    Returns
    -------
    ListeningSettings

    Raises
    ------
    SchemaError
        The file is missing or not TOML, or a section or key is unknown, of the wrong type
        or out of range (the message names the file and the key).
    """
    file = Path(path) if path is not None else default_settings_path()
    source = str(file)
    try:
        with open(file, "rb") as fh:
            data = tomllib.load(fh)
    except OSError as exc:
        raise SchemaError(f"cannot read ({exc.strerror or exc})", source=source) from None
    except tomllib.TOMLDecodeError as exc:
        raise SchemaError(f"not valid TOML ({exc})", source=source) from None
    unknown = sorted(set(data) - set(RANGES))
    if unknown:
        raise SchemaError(f"unknown section [{unknown[0]}] (known: {sorted(RANGES)})",
                          source=source)
    chosen: dict[str, dict[str, float]] = {}
    for section, ranges in RANGES.items():
        table = data.get(section, {})
        if not isinstance(table, dict):
            raise SchemaError(f"{section} must be a table ([{section}])", source=source)
        for key, raw in table.items():
            if key not in ranges:
                raise SchemaError(f"unknown key {section}.{key} (known: {sorted(ranges)})",
                                  source=source)
            chosen.setdefault(section, {})[key] = _value(raw, *ranges[key],
                                                         f"{section}.{key}", source)
    return ListeningSettings(replace(ControllerSettings(), **chosen.get("controller", {})),
                             replace(TeacherThresholds(), **chosen.get("teacher", {})))


def settings_keys() -> dict[str, tuple[str, ...]]:
    """Keys of each section, as the dataclasses name them (for the tests and the docs)."""
    return {"controller": tuple(f.name for f in fields(ControllerSettings)),
            "teacher": tuple(f.name for f in fields(TeacherThresholds))}
