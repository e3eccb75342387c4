"""The performance-rules configuration: shipped TOML defaults, validated, overridable.

The defaults live in ``pipelines/perform/rules.toml`` (package data), plus what the
instrument facts (:mod:`data_schemas.instruments`) already say: the bow lanes
(``[dynamics]`` beta and velocity), each instrument's ``bow_length`` and the bow's
``max_acceleration``. The bow force at each lane is the rules' own table in newtons per
instrument and string (``[bow_force.<instrument>]``, :func:`bow_force`). A user file given
with ``--config`` is merged over them key by key, so it may hold only what it changes
(including those three).
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
from data_schemas.instruments import (
    INSTRUMENT_NAMES,
    check_instrument_names,
    dynamics_table,
    instrument_facts,
    limits,
)

_N_LEVELS = 10
#: dB a level below pppp or above ffff (velocity and force scaled together at the end lane's
#: beta).
QUIET_DB = 3.0
#: The dynamic scale's last level (ffff).
TOP_LEVEL = float(_N_LEVELS - 1)


def default_config() -> dict[str, Any]:
    """Return a copy of the shipped rules configuration (read once, validated).

    A fresh copy each call: a caller that changes its copy changes no one else's.
    """
    return _copy(_shipped_config())


@lru_cache(maxsize=1)
def _shipped_config() -> dict[str, Any]:
    text = resources.files("pipelines").joinpath("perform/rules.toml").read_text("utf-8")
    config = _with_facts(tomllib.loads(text))
    validate_config(config, source="pipelines/perform/rules.toml")
    return config


def _with_facts(config: dict[str, Any]) -> dict[str, Any]:
    """Add the defaults that the instrument facts hold (dynamics, bow length, acceleration)."""
    lanes = dynamics_table("bow_lanes")
    config["dynamics"] = {"beta": list(lanes.beta), "velocity": list(lanes.velocity)}
    config["instruments"] = {name: {"bow_length": instrument_facts(name).bow_length}
                             for name in INSTRUMENT_NAMES}
    config["bow"]["max_acceleration"] = limits().max_bow_acceleration
    return config


def load_config(path: str | os.PathLike | None = None, *,
                base: dict[str, Any] | None = None) -> dict[str, Any]:
    """Return the defaults (or a copy of ``base``) merged with the TOML file at ``path``.

    ``base``: a configuration already loaded (another file's), for files read in layers.
    The result is validated.

    Raises
    ------
    ParameterError
        The file is missing, not TOML, or a value is out of range (names file and key).
    """
    config = default_config() if base is None else _copy(base)
    if path is None:
        return config
    path = Path(path)
    try:
        user = tomllib.loads(path.read_text("utf-8"))
    except FileNotFoundError:
        raise ParameterError(f"--config {path}: file not found") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"--config {path}: not valid TOML ({exc})") from None
    _refuse_multiples(user, str(path))
    _merge(config, user, str(path), "")
    validate_config(config, source=str(path))
    return config


def _copy(config: dict[str, Any]) -> dict[str, Any]:
    return {k: _copy(v) if isinstance(v, dict) else (list(v) if isinstance(v, list) else v)
            for k, v in config.items()}


def _refuse_multiples(user: dict[str, Any], source: str) -> None:
    """Name the keys of the force table in multiples, which the newton table replaced."""
    old = ["dynamics.force"] if "force" in user.get("dynamics", {}) else []
    old += [f"instruments.{name}.force_scale" for name, inst in
            user.get("instruments", {}).items() if isinstance(inst, dict) and
            "force_scale" in inst]
    if old:
        raise ParameterError(f"{source}: {', '.join(old)}: the rules' bow forces are now "
                             "newtons per string and dynamic level, [bow_force.<instrument>] "
                             "<string> = [10 values, N] (see pipelines/perform/rules.toml)")


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


#: Largest accepted value of each positive setting (sane bounds, far above useful values):
#: per section, per key or ``"*"`` for every key of the section.
UPPER_LIMITS: dict[str, dict[str, float]] = {
    "frames": {"interval": 0.1},
    "bow": {"max_acceleration": 100.0, "short_stroke_acceleration": 100.0,
            "min_speed_scale": 1.0, "max_speed_scale": 10.0, "retake_gap": 10.0,
            "region_span": 1.0, "slowed_min_beta": 0.45},
    "articulations": {"*": 10.0, "bite_force": 4.0, "bite_hold": 1.0, "bite_time": 1.0,
                      "rise_time": 1.0},
    "techniques": {"*": 10.0},
    "instruments": {"bow_length": 1.5},
    "dynamics": {"beta": 0.5, "velocity": 5.0},
    "bow_force": {"*": 50.0},
    "skill": {"pitch_sigma": 12.0, "onset_sigma": 1.0},
    "vibrato": {"*": 20.0, "extent": 100.0, "onset_share": 1.0},
    "ornaments": {"trill_subdivision": 32.0, "trill_min_rate": 30.0, "trill_max_rate": 30.0,
                  "ornament_note": 0.5, "appoggiatura_share": 0.9, "shift_interval": 24.0,
                  "portamento_time": 0.5},
    "harmonics": {"highest_node": 12.0, "min_beta": 0.2, "segment_beta": 4.0, "force": 2.0},
    "phrasing": {"phrase_length": 600.0, "phrase_min_length": 600.0, "phrase_depth": 30.0,
                 "turn": 0.95, "max_step_db": 30.0, "even_depth": 1.0, "clear_break": 1.0,
                 "chord_db": 12.0, "slow_note": 60.0, "slow_step": 10.0},
}


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and \
        bool(np.isfinite(value))


def _upper(section: str, key: str) -> float:
    table = UPPER_LIMITS[section]
    return table.get(key, table.get("*", np.inf))


def _positive(config: dict[str, Any], section: str, key: str, source: str) -> None:
    value = config[section][key]
    upper = _upper(section, key)
    if not _is_number(value) or value <= 0 or value > upper:
        raise ParameterError(f"{source}: {section}.{key}={value!r} must be > 0 and <= {upper}")


def _numbers(values: object, name: str, count: int, lower: str, upper: float,
             source: str) -> np.ndarray:
    """A list of ``count`` finite numbers above ``lower`` (``"> 0"`` or ``">= 0"``)."""
    ok = isinstance(values, list) and len(values) == count and all(map(_is_number, values))
    array = np.asarray(values if ok else [], dtype=np.float64)
    if ok:
        ok = bool(np.all(array > 0 if lower == "> 0" else array >= 0) and np.all(array <= upper))
    if not ok:
        shown = repr(values) if len(repr(values)) <= 80 else f"{repr(values)[:77]}..."
        raise ParameterError(f"{source}: {name} must hold {count} numbers {lower} and <= "
                             f"{upper}, got {shown}")
    return array


def validate_config(config: dict[str, Any], source: str = "<config>") -> None:
    """Check the rules configuration; raise :class:`ParameterError` naming the key.

    Every setting must be a finite number within its range; positive settings are also
    bounded by :data:`UPPER_LIMITS`.

    Examples
    --------
    >>> validate_config(default_config())
    >>> bad = _copy(default_config())
    >>> bad["frames"]["interval"] = 1e300
    >>> validate_config(bad, "my.toml")
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: my.toml: frames.interval=1e+300 must be > 0 and <= 0.1
    """
    for key in ("beta", "velocity"):
        _numbers(config["dynamics"][key], f"dynamics.{key}", _N_LEVELS, "> 0",
                 _upper("dynamics", key), source)
    if np.any(np.asarray(config["dynamics"]["beta"]) >= 0.5):
        raise ParameterError(f"{source}: dynamics.beta values must be < 0.5")
    for name, inst in config["instruments"].items():
        value, upper = inst.get("bow_length"), _upper("instruments", "bow_length")
        if not _is_number(value) or not 0 < value <= upper:
            raise ParameterError(f"{source}: instruments.{name}.bow_length={value!r} must be "
                                 f"> 0 and <= {upper}")
    _validate_bow_force(config, source)
    _positive(config, "frames", "interval", source)
    for key in ("max_acceleration", "short_stroke_acceleration", "min_speed_scale",
                "max_speed_scale", "retake_gap", "region_span", "slowed_min_beta"):
        _positive(config, "bow", key, source)
    margin = config["bow"]["margin"]
    if not _is_number(margin) or not 0 <= margin < 0.5:
        raise ParameterError(f"{source}: bow.margin={margin!r} must be in [0, 0.5)")
    check_instrument_names(config["bow"]["pressing_limit"], "bow.pressing_limit", source)
    _validate_node_guard(config["bow"], source)
    for key in config["articulations"]:
        _positive(config, "articulations", key, source)
    for key in config["techniques"]:
        _positive(config, "techniques", key, source)
    for key, value in config["bow_regions"].items():
        if not _is_number(value) or not 0 <= value <= 1:
            raise ParameterError(f"{source}: bow_regions.{key}={value!r} must be in [0, 1]")
    _validate_expression(config, source)
    _validate_loudness(config, source)
    _validate_phrasing(config, source)
    for key in ("min_beta", "segment_beta", "force"):
        _positive(config, "harmonics", key, source)
    node = config["harmonics"]["highest_node"]
    if not isinstance(node, int) or isinstance(node, bool) or not 2 <= node <= 12:
        raise ParameterError(f"{source}: harmonics.highest_node={node!r} must be a whole "
                             "number from 2 to 12")
    for key in ("pitch_sigma", "onset_sigma"):
        _numbers(config["skill"][key], f"skill.{key} (levels 0..3)", 4, ">= 0",
                 _upper("skill", key), source)


def _validate_node_guard(bow: dict[str, Any], source: str) -> None:
    """``[bow] node_guard`` (whole mode numbers from 2 to 20) and ``node_width`` (0..0.5)."""
    nodes = bow["node_guard"]
    if not isinstance(nodes, list) or not all(
            isinstance(n, int) and not isinstance(n, bool) and 2 <= n <= 20 for n in nodes):
        raise ParameterError(f"{source}: bow.node_guard={nodes!r} must be a list of whole "
                             "mode numbers from 2 to 20")
    width = bow["node_width"]
    if not _is_number(width) or not 0 <= width < 0.5:
        raise ParameterError(f"{source}: bow.node_width={width!r} must be in [0, 0.5) (mode "
                             "numbers: neighbouring zones may not overlap)")


def _validate_bow_force(config: dict[str, Any], source: str) -> None:
    """``[bow_force.<instrument>]``: every string of every instrument, 10 newtons each."""
    table = config.get("bow_force", {})
    for name in INSTRUMENT_NAMES:
        rows = table.get(name, {})
        for string in instrument_facts(name).string_names:
            if string not in rows:
                raise ParameterError(f"{source}: bow_force.{name}.{string} is missing (one row "
                                     "of 10 forces in N per string)")
            _numbers(rows[string], f"bow_force.{name}.{string} (N, levels pppp..ffff)",
                     _N_LEVELS, "> 0", _upper("bow_force", "*"), source)


def _validate_loudness(config: dict[str, Any], source: str) -> None:
    """``[loudness]``: a switch, a target in LUFS, a non-decreasing level curve, shifts."""
    cfg = config["loudness"]
    if not isinstance(cfg["enabled"], bool):
        raise ParameterError(f"{source}: loudness.enabled={cfg['enabled']!r} must be true or "
                             "false")
    if not _is_number(cfg["mf"]) or not -70.0 <= cfg["mf"] <= 0.0:
        raise ParameterError(f"{source}: loudness.mf={cfg['mf']!r} must be in [-70, 0] LUFS")
    curve = cfg["level_db"]
    ok = isinstance(curve, list) and len(curve) == _N_LEVELS and all(map(_is_number, curve))
    if not ok or np.any(np.diff(curve) < 0) or np.any(np.abs(curve) > 60.0):
        raise ParameterError(f"{source}: loudness.level_db must hold {_N_LEVELS} "
                             f"non-decreasing numbers within +-60 dB, got {curve!r}")
    if not _is_number(cfg["max_shift"]) or not 0.0 <= cfg["max_shift"] <= 9.0:
        raise ParameterError(f"{source}: loudness.max_shift={cfg['max_shift']!r} must be in "
                             "[0, 9] levels")
    if not _is_number(cfg["below_pppp"]) or not 0.0 <= cfg["below_pppp"] <= 5.0:
        raise ParameterError(f"{source}: loudness.below_pppp={cfg['below_pppp']!r} must be in "
                             "[0, 5] levels")
    if not _is_number(cfg["above_ffff"]) or not 0.0 <= cfg["above_ffff"] <= 2.0:
        raise ParameterError(f"{source}: loudness.above_ffff={cfg['above_ffff']!r} must be in "
                             "[0, 2] levels")
    rehearsals = cfg["rehearsals"]
    if isinstance(rehearsals, bool) or not isinstance(rehearsals, int) or \
            not 0 <= rehearsals <= 5:
        raise ParameterError(f"{source}: loudness.rehearsals={rehearsals!r} must be a whole "
                             "number in [0, 5]")
    for key, top, unit in (("rehearsal_tolerance_db", 6.0, "dB"),
                           ("rehearsal_max_shift", 9.0, "levels")):
        if not _is_number(cfg[key]) or not 0.0 < cfg[key] <= top:
            raise ParameterError(f"{source}: loudness.{key}={cfg[key]!r} must be in "
                                 f"(0, {top:g}] {unit}")


def _validate_phrasing(config: dict[str, Any], source: str) -> None:
    """``[phrasing]``: a switch, positive lengths and step, depths >= 0, turn inside (0, 1)."""
    cfg = config["phrasing"]
    if not isinstance(cfg["enabled"], bool):
        raise ParameterError(f"{source}: phrasing.enabled={cfg['enabled']!r} must be true or "
                             "false")
    for key in ("phrase_length", "phrase_min_length", "turn", "max_step_db", "clear_break",
                "slow_note", "slow_step"):
        _positive(config, "phrasing", key, source)
    if cfg["slow_step"] < 1:
        raise ParameterError(f"{source}: phrasing.slow_step={cfg['slow_step']!r} must be >= 1 "
                             "(a slow note steps at least as much as a quick one)")
    for key in ("phrase_depth", "chord_db", "even_depth"):
        value, upper = cfg[key], _upper("phrasing", key)
        if not _is_number(value) or not 0 <= value <= upper:
            raise ParameterError(f"{source}: phrasing.{key}={value!r} must be in [0, {upper}]")


_VIBRATO_POSITIVE = ("rate", "onset_delay", "fade_in", "min_duration")
_VIBRATO_NONNEGATIVE = ("extent", "rate_sigma", "extent_sigma", "performer_rate_sigma",
                        "performer_extent_sigma", "dynamic_rate", "dynamic_extent",
                        "length_extent", "phrase_end_extent", "onset_share")


def _validate_expression(config: dict[str, Any], source: str) -> None:
    """``[vibrato]`` and ``[intonation]``: numbers in range, switches boolean."""
    vib = config["vibrato"]
    for key in ("enabled", "open_strings"):
        if not isinstance(vib[key], bool):
            raise ParameterError(f"{source}: vibrato.{key}={vib[key]!r} must be true or false")
    for key in _VIBRATO_POSITIVE:
        _positive(config, "vibrato", key, source)
    for key in _VIBRATO_NONNEGATIVE:
        upper = _upper("vibrato", key)
        if not _is_number(vib[key]) or not 0 <= vib[key] <= upper:
            raise ParameterError(f"{source}: vibrato.{key}={vib[key]!r} must be a number "
                                 f">= 0 and <= {upper}")
    if not 3.0 <= vib["rate"] <= 9.0:
        raise ParameterError(f"{source}: vibrato.rate={vib['rate']!r} must be in [3, 9] Hz")
    if vib["enabled"] and config["frames"]["interval"] > 1.0 / (8.0 * vib["rate"]):
        raise ParameterError(f"{source}: frames.interval={config['frames']['interval']!r} s "
                             f"is too coarse for a {vib['rate']} Hz vibrato (at most "
                             f"{1.0 / (8.0 * vib['rate']):.4f} s: 8 frames a cycle)")
    _validate_ornaments(config, source)
    into = config["intonation"]
    if not isinstance(into["by_ear"], bool):
        raise ParameterError(f"{source}: intonation.by_ear={into['by_ear']!r} must be true "
                             "or false")
    if not _is_number(into["sigma"]) or not 0 <= into["sigma"] <= 100:
        raise ParameterError(f"{source}: intonation.sigma={into['sigma']!r} must be in "
                             "[0, 100] cents")
    if not _is_number(into["semitone_step"]) or abs(into["semitone_step"]) > 50:
        raise ParameterError(f"{source}: intonation.semitone_step="
                             f"{into['semitone_step']!r} must be in [-50, 50] cents")


def _validate_ornaments(config: dict[str, Any], source: str) -> None:
    orn = config["ornaments"]
    for key in ("trill_subdivision", "trill_min_rate", "trill_max_rate", "ornament_note",
                "appoggiatura_share", "shift_interval", "portamento_time"):
        _positive(config, "ornaments", key, source)
    if orn["trill_min_rate"] > orn["trill_max_rate"]:
        raise ParameterError(f"{source}: ornaments.trill_min_rate={orn['trill_min_rate']!r} "
                             f"is above trill_max_rate={orn['trill_max_rate']!r}")
    if orn["trill_start"] not in ("upper", "main"):
        raise ParameterError(f"{source}: ornaments.trill_start={orn['trill_start']!r} must be "
                             "'upper' or 'main'")
    if not isinstance(orn["trill_nachschlag"], bool):
        raise ParameterError(f"{source}: ornaments.trill_nachschlag="
                             f"{orn['trill_nachschlag']!r} must be true or false")
    if config["frames"]["interval"] > 1.0 / (2.0 * orn["trill_max_rate"]):
        raise ParameterError(f"{source}: frames.interval={config['frames']['interval']!r} s "
                             f"is too coarse for trills of {orn['trill_max_rate']} notes/s")


def beyond_lanes(level: np.ndarray) -> np.ndarray:
    """Levels beyond the lanes' table: below pppp (negative), above ffff (positive), else 0.

    Examples
    --------
    >>> beyond_lanes(np.array([-2.0, 4.0, 9.5])).tolist()
    [-2.0, 0.0, 0.5]
    """
    level = np.asarray(level, dtype=np.float64)
    return np.minimum(level, 0.0) + np.maximum(level - TOP_LEVEL, 0.0)


def dynamic_table(config: dict[str, Any], key: str, level: np.ndarray) -> np.ndarray:
    """Interpolate a bow lane (``beta`` or ``velocity``) at fractional dynamic levels.

    Parameters
    ----------
    config : dict
        Rules configuration.
    key : str
        ``beta`` or ``velocity`` (m/s).
    level : np.ndarray [shape=(n,)]
        Dynamic levels on the 0..9 scale; below 0 (softer than pppp, where evening out
        loudness needs it) the pppp lane's beta with velocity and force (:func:`bow_force`)
        both scaled down by :data:`QUIET_DB` dB a level: the Helmholtz window's edges
        (F_min ~ v / beta^2, F_max ~ v / beta) scale with the velocity, so the note stays as
        far inside it as at pppp, and its amplitude (~ v / beta) falls by the same dB. Above
        9 (louder than ffff) the same law scales the ffff lane up.

    Returns
    -------
    np.ndarray [shape=(n,)]

    Examples
    --------
    >>> cfg = load_config()
    >>> [round(float(x), 4) for x in dynamic_table(cfg, "velocity", np.array([0.0, -2.0]))]
    [0.074, 0.0371]
    >>> float(dynamic_table(cfg, "beta", np.array([-2.0]))[0])
    0.185
    """
    if key not in ("beta", "velocity"):
        raise ParameterError(f"dynamic_table: {key!r} is not a bow lane (beta or velocity; "
                             "the force is bow_force(config, instrument, string, level))")
    return _at_levels(config["dynamics"][key], level, scaled=key == "velocity")


def bow_force(config: dict[str, Any], instrument: str, string: int,
              level: np.ndarray) -> np.ndarray:
    """The rules' bow force (N) on one string at fractional dynamic levels.

    Parameters
    ----------
    config : dict
        Rules configuration (its ``[bow_force.<instrument>]`` table).
    instrument : str
        ``violin``, ``viola`` or ``cello``.
    string : int
        String index, 0 = lowest.
    level : np.ndarray [shape=(n,)]
        Dynamic levels on the 0..9 scale; beyond pppp and ffff scaled like the velocity
        (:func:`dynamic_table`).

    Returns
    -------
    np.ndarray [shape=(n,)], N

    Examples
    --------
    >>> cfg = load_config()
    >>> float(bow_force(cfg, "violin", 1, np.array([5.0]))[0])     # D string, mf
    2.145
    >>> ratio = bow_force(cfg, "cello", 0, np.array([10.0, 9.0]))
    >>> round(float(ratio[0] / ratio[1]), 3)       # 3 dB a level above ffff
    1.413
    """
    rows = config["bow_force"][instrument]
    return _at_levels(rows[instrument_facts(instrument).string_names[string]], level, True)


def _at_levels(table: list[float], level: np.ndarray, scaled: bool) -> np.ndarray:
    """A per-level table at fractional levels; ``scaled``: by QUIET_DB dB a level beyond."""
    table = np.asarray(table, dtype=np.float64)
    level = np.asarray(level, dtype=np.float64)
    out = np.interp(level, np.arange(table.size), table)
    if scaled:
        out = out * 10.0 ** (QUIET_DB * beyond_lanes(level) / 20.0)
    return out
