"""The performance-rules configuration: shipped TOML defaults, validated, overridable.

The defaults live in ``pipelines/perform/rules.toml`` (package data), plus what the
instrument facts (:mod:`data_schemas.instruments`) already say: the dynamics table
(``[dynamics]``, the facts' bow lanes), each instrument's ``bow_length`` and the bow's
``max_acceleration``. A user file given with ``--config`` is merged over them key by key, so
it may hold only what it changes (including those three).
"""

from __future__ import annotations

import os
import tomllib
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from data_schemas.errors import ParameterError
from data_schemas.instruments import INSTRUMENT_NAMES, dynamics_table, instrument_facts, limits

_N_LEVELS = 10


@lru_cache(maxsize=1)
def default_config() -> dict[str, Any]:
    """Return the shipped rules configuration (loaded once, validated)."""
    text = resources.files("pipelines").joinpath("perform/rules.toml").read_text("utf-8")
    config = _with_facts(tomllib.loads(text))
    validate_config(config, source="pipelines/perform/rules.toml")
    return config


def _with_facts(config: dict[str, Any]) -> dict[str, Any]:
    """Add the defaults that the instrument facts hold (dynamics, bow length, acceleration)."""
    lanes = dynamics_table("bow_lanes")
    config["dynamics"] = {"beta": list(lanes.beta), "velocity": list(lanes.velocity),
                          "force": list(lanes.force)}
    for name in INSTRUMENT_NAMES:
        config["instruments"][name]["bow_length"] = instrument_facts(name).bow_length
    config["bow"]["max_acceleration"] = limits().max_bow_acceleration
    return config


def load_config(path: str | os.PathLike | None = None) -> dict[str, Any]:
    """Return the defaults merged with the TOML file at ``path`` (if any), validated.

    Raises
    ------
    ParameterError
        The file is missing, not TOML, or a value is out of range (names file and key).
    """
    config = _copy(default_config())
    if path is None:
        return config
    path = Path(path)
    try:
        user = tomllib.loads(path.read_text("utf-8"))
    except FileNotFoundError:
        raise ParameterError(f"--config {path}: file not found") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"--config {path}: not valid TOML ({exc})") from None
    _merge(config, user, str(path), "")
    validate_config(config, source=str(path))
    return config


def _copy(config: dict[str, Any]) -> dict[str, Any]:
    return {k: _copy(v) if isinstance(v, dict) else (list(v) if isinstance(v, list) else v)
            for k, v in config.items()}


def _merge(base: dict[str, Any], over: dict[str, Any], source: str, prefix: str) -> None:
    for key, value in over.items():
        name = f"{prefix}{key}"
        if key not in base:
            raise ParameterError(f"{source}: unknown setting '{name}'")
        if isinstance(base[key], dict):
            if not isinstance(value, dict):
                raise ParameterError(f"{source}: '{name}' must be a table")
            _merge(base[key], value, source, f"{name}.")
        else:
            base[key] = value


def _positive(config: dict[str, Any], section: str, key: str, source: str,
              upper: float | None = None) -> None:
    value = config[section][key]
    if not isinstance(value, int | float) or not np.isfinite(value) or value <= 0 or \
            (upper is not None and value > upper):
        limit = f" and <= {upper}" if upper is not None else ""
        raise ParameterError(f"{source}: {section}.{key}={value!r} must be > 0{limit}")


def validate_config(config: dict[str, Any], source: str = "<config>") -> None:
    """Check the rules configuration; raise :class:`ParameterError` naming the key."""
    for key in ("beta", "velocity", "force"):
        values = np.asarray(config["dynamics"][key], dtype=np.float64)
        if values.shape != (_N_LEVELS,) or not np.all(np.isfinite(values)) or \
                np.any(values <= 0):
            raise ParameterError(
                f"{source}: dynamics.{key} must hold {_N_LEVELS} positive numbers "
                f"(pppp..ffff), got {config['dynamics'][key]!r}")
    if np.any(np.asarray(config["dynamics"]["beta"]) >= 0.5):
        raise ParameterError(f"{source}: dynamics.beta values must be < 0.5")
    for name, inst in config["instruments"].items():
        for key in ("force_scale", "bow_length"):
            value = inst.get(key)
            if not isinstance(value, int | float) or value <= 0:
                raise ParameterError(f"{source}: instruments.{name}.{key}={value!r} must be > 0")
    _positive(config, "frames", "interval", source, upper=0.1)
    for key in ("max_acceleration", "min_speed_scale", "max_speed_scale", "retake_gap",
                "region_span"):
        _positive(config, "bow", key, source)
    if not 0 <= config["bow"]["margin"] < 0.5:
        raise ParameterError(f"{source}: bow.margin={config['bow']['margin']!r} must be in "
                             "[0, 0.5)")
    for key in config["articulations"]:
        _positive(config, "articulations", key, source)
    for key in config["techniques"]:
        _positive(config, "techniques", key, source)
    for key, value in config["bow_regions"].items():
        if not isinstance(value, int | float) or not 0 <= value <= 1:
            raise ParameterError(f"{source}: bow_regions.{key}={value!r} must be in [0, 1]")
    _validate_expression(config, source)
    for key in ("pitch_sigma", "onset_sigma"):
        values = config["skill"][key]
        if len(values) != 4 or any(v < 0 for v in values):
            raise ParameterError(f"{source}: skill.{key} must hold 4 numbers >= 0 "
                                 f"(levels 0..3), got {values!r}")


_VIBRATO_POSITIVE = ("rate", "onset_delay", "fade_in", "min_duration")
_VIBRATO_NONNEGATIVE = ("extent", "rate_sigma", "extent_sigma", "performer_rate_sigma",
                        "performer_extent_sigma", "dynamic_rate", "dynamic_extent",
                        "length_extent", "phrase_end_extent", "onset_share")


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and \
        bool(np.isfinite(value))


def _validate_expression(config: dict[str, Any], source: str) -> None:
    """``[vibrato]`` and ``[intonation]``: numbers in range, switches boolean."""
    vib = config["vibrato"]
    for key in ("enabled", "open_strings"):
        if not isinstance(vib[key], bool):
            raise ParameterError(f"{source}: vibrato.{key}={vib[key]!r} must be true or false")
    for key in _VIBRATO_POSITIVE:
        _positive(config, "vibrato", key, source, upper=20.0)
    for key in _VIBRATO_NONNEGATIVE:
        if not _number(vib[key]) or vib[key] < 0:
            raise ParameterError(f"{source}: vibrato.{key}={vib[key]!r} must be a number >= 0")
    if not 3.0 <= vib["rate"] <= 9.0:
        raise ParameterError(f"{source}: vibrato.rate={vib['rate']!r} must be in [3, 9] Hz")
    if vib["extent"] > 100.0:
        raise ParameterError(f"{source}: vibrato.extent={vib['extent']!r} must be <= 100 "
                             "cents")
    if vib["enabled"] and config["frames"]["interval"] > 1.0 / (8.0 * vib["rate"]):
        raise ParameterError(f"{source}: frames.interval={config['frames']['interval']!r} s "
                             f"is too coarse for a {vib['rate']} Hz vibrato (at most "
                             f"{1.0 / (8.0 * vib['rate']):.4f} s: 8 frames a cycle)")
    into = config["intonation"]
    if not _number(into["sigma"]) or not 0 <= into["sigma"] <= 100:
        raise ParameterError(f"{source}: intonation.sigma={into['sigma']!r} must be in "
                             "[0, 100] cents")
    if not _number(into["semitone_step"]) or abs(into["semitone_step"]) > 50:
        raise ParameterError(f"{source}: intonation.semitone_step="
                             f"{into['semitone_step']!r} must be in [-50, 50] cents")


def dynamic_table(config: dict[str, Any], key: str, level: np.ndarray) -> np.ndarray:
    """Interpolate a per-dynamic table at fractional levels.

    Parameters
    ----------
    config : dict
        Rules configuration.
    key : str
        ``beta``, ``velocity`` (m/s) or ``force`` (multiples of the string's reference force).
    level : np.ndarray [shape=(n,)]
        Dynamic levels on the 0..9 scale.

    Returns
    -------
    np.ndarray [shape=(n,)]
    """
    table = np.asarray(config["dynamics"][key], dtype=np.float64)
    return np.interp(np.asarray(level, dtype=np.float64), np.arange(table.size), table)
