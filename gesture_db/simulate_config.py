"""The simulated performer's constants and styles, from ``gesture_db/config/simulate.toml``.

:func:`simulator_config` returns the shipped constants (validated once); :class:`Performer`
is one style; :data:`PERFORMERS` are the shipped styles and :func:`load_performers` reads
others from a TOML file of ``[[performer]]`` entries (each sets only what differs from the
shipped ``[performer_defaults]``).
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, fields, replace
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from data_schemas.errors import ParameterError


@dataclass(frozen=True)
class Performer:
    """The style of a simulated performer.

    Parameters
    ----------
    name : str
        Label written to the annotation.
    velocity_scale, force_scale, beta_scale : float
        Multipliers of the per-dynamic starting values.
    accel : float
        Typical bow-change acceleration (m/s^2), within 6-30.
    martele_accel : float
        Attack acceleration of martele strokes (m/s^2).
    variability : float
        Relative standard deviation of trial-to-trial variation of velocity, force, beta.
    ioi_sd : float
        Relative standard deviation of inter-onset intervals (timing deviations).
    tempo_scale : float
        Overall tempo factor applied to note durations (> 1 = slower).
    force_dip : float
        Relative dip of the force at a bow change.
    vibrato_extent : float
        Peak vibrato extent (cents) at mf on long detache and legato notes.
    vibrato_rate : float
        Vibrato rate (Hz) at mf.
    vibrato_delay : float
        Time (s) from a note's onset to the start of its vibrato.
    intonation_sd : float
        Standard deviation (cents) of the pitch offset from note to note.
    shift_glide : float
        Duration (s) of the slide into a shift (see :mod:`gesture_db.playing_left_hand`).
    staccato_fill : float
        Fraction of a staccato note during which the bow moves.
    finger_lead : float
        How long before a bow change the finger moves (s, mean).
    crescendo : float
        Relative swell of velocity and force over a run (phrase), first to last note;
        sustained notes inside a run tilt with it.
    accent : float
        Relative extra force on the first note of a slur or a run.
    phrase_arch : float
        Relative arch of velocity and force over a run of three notes or more: times
        ``1 + phrase_arch (sin(pi place) - 0.5)``, fullest in the middle.
    """

    name: str
    velocity_scale: float
    force_scale: float
    beta_scale: float
    accel: float
    martele_accel: float
    variability: float
    ioi_sd: float
    tempo_scale: float
    force_dip: float
    vibrato_extent: float
    vibrato_rate: float
    vibrato_delay: float
    intonation_sd: float
    shift_glide: float
    staccato_fill: float
    finger_lead: float
    crescendo: float
    accent: float
    phrase_arch: float


_FIELDS = tuple(f.name for f in fields(Performer) if f.name != "name")


def _config_path() -> Path:
    return Path(str(resources.files("gesture_db") / "config" / "simulate.toml"))


def _check_numbers(table: Any, where: str, source: str) -> None:
    """Every leaf of ``table`` must be a finite number (or a list of them)."""
    if isinstance(table, dict):
        for key, value in table.items():
            if key != "name":
                _check_numbers(value, f"{where}.{key}" if where else key, source)
    elif isinstance(table, list):
        for value in table:
            _check_numbers(value, where, source)
    elif isinstance(table, bool) or not isinstance(table, int | float) or \
            not math.isfinite(table):
        raise ParameterError(f"{source}: {where} = {table!r} must be a finite number")


@cache
def simulator_config() -> dict[str, Any]:
    """The shipped constants of the simulated performer (sections of ``simulate.toml``).

    Raises
    ------
    ParameterError
        A section is missing or a value is not a finite number.
    """
    path = _config_path()
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    for section in ("script", "timing", "magnitudes", "stroke", "bow", "left_hand", "noise",
                    "alignment", "variants", "performer_defaults", "performer"):
        if section not in data:
            raise ParameterError(f"{path}: no [{section}] section")
    _check_numbers(data, "", str(path))
    return data


def _performer(entry: dict[str, Any], defaults: dict[str, Any], source: str) -> Performer:
    unknown = sorted(set(entry) - set(_FIELDS) - {"name"})
    if unknown or "name" not in entry:
        raise ParameterError(f"{source}: a [[performer]] needs a name and knows only "
                             f"{list(_FIELDS)} (got {unknown or 'no name'})")
    values = {**defaults, **entry}
    for key in _FIELDS:
        value = values.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float) or \
                not math.isfinite(value) or value < 0:
            raise ParameterError(f"{source}: performer {entry['name']!r}: {key} = {value!r} "
                                 "must be a number >= 0")
    return Performer(name=str(values["name"]), **{k: float(values[k]) for k in _FIELDS})


def load_performers(path: str | os.PathLike | None = None) -> tuple[Performer, ...]:
    """Read performer styles from a TOML file of ``[[performer]]`` entries.

    Parameters
    ----------
    path : path-like, optional
        A file like the ``[[performer]]`` part of ``gesture_db/config/simulate.toml``;
        each entry gives ``name`` and the fields it changes from the shipped
        ``[performer_defaults]``. None: the shipped performers.

    Raises
    ------
    ParameterError
        Missing file, bad TOML, no performer, an unknown field or a bad value.
    """
    config = simulator_config()
    defaults = config["performer_defaults"]
    if path is None:
        entries, source = config["performer"], str(_config_path())
    else:
        source = str(path)
        try:
            with open(path, "rb") as fh:
                entries = tomllib.load(fh).get("performer", [])
        except FileNotFoundError:
            raise ParameterError(f"{source}: file not found") from None
        except tomllib.TOMLDecodeError as exc:
            raise ParameterError(f"{source}: not valid TOML ({exc})") from None
    if not entries:
        raise ParameterError(f"{source}: no [[performer]] entries")
    return tuple(_performer(e, defaults, source) for e in entries)


#: The shipped styles; further performers are random variations of these.
PERFORMERS = load_performers()


def make_performers(n: int, rng: np.random.Generator,
                    bases: tuple[Performer, ...] = PERFORMERS) -> list[Performer]:
    """Return ``n`` performer styles: ``bases`` first, then random variants of them."""
    var = simulator_config()["variants"]
    out = list(bases[:n])
    while len(out) < n:
        base = bases[len(out) % len(bases)]
        out.append(replace(
            base, name=f"{base.name}{len(out)}",
            velocity_scale=base.velocity_scale * float(np.exp(rng.normal(0, var["velocity_sd"]))),
            force_scale=base.force_scale * float(np.exp(rng.normal(0, var["force_sd"]))),
            beta_scale=base.beta_scale * float(np.exp(rng.normal(0, var["beta_sd"]))),
            accel=float(np.clip(base.accel * np.exp(rng.normal(0, var["accel_sd"])),
                                *var["accel_range"])),
            tempo_scale=base.tempo_scale * float(np.exp(rng.normal(0, var["tempo_sd"])))))
    return out


__all__ = ["PERFORMERS", "Performer", "load_performers", "make_performers", "simulator_config"]
