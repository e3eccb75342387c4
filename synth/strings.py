"""Instrument and string constants: the facts of the instrument plus the string physics.

Open-string pitches and names, speaking lengths, tuning and body scale are the instrument
facts (:mod:`data_schemas.instruments`); ``synth/config/strings.toml`` adds each string's
physics (tension, diameter, density, stiffness, friction, damping, reference force, bowed
pitch offset) and records where each number comes from. :func:`load_instrument` returns
plain frozen dataclasses in SI units; open strings are tuned to their nominal pitch on load
(by default so that the bowed string sounds it, as a player tunes).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, replace
from functools import cache
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from data_schemas.errors import ParameterError, SchemaError
from data_schemas.instruments import INSTRUMENT_NAMES, instrument_facts, limits

if TYPE_CHECKING:
    import numpy as np

#: Keys of the instrument facts that a strings file must not repeat.
_FACT_KEYS = {"name", "midi_pitch", "length", "bow_hair_length", "body_scale", "tuning_a4"}


@dataclass(frozen=True)
class StringConstants:
    """Physical constants of one string, SI units.

    Attributes
    ----------
    name : str
        Letter name of the open string (``"G"``).
    midi_pitch : int
        Nominal pitch of the open string.
    tension : float, N
    length : float, m
        Speaking length, bridge to nut.
    diameter : float, m
    linear_density : float, kg/m
    youngs_modulus : float, Pa
    mu_s, mu_d : float
        Static and dynamic friction coefficients of the hyperbolic friction curve.
    v0 : float, m/s
        Velocity scale of the friction curve.
    damping_b1, damping_b2 : float, 1/s
        Modal decay rates ``r_n = b1 + b2 (f_n / f_1 - 1)**2``.
    finger_stiffness : float, N/m
    finger_damping : float, N s/m
        The stopping finger's spring-damper.
    touch_stiffness : float, N/m
    touch_damping : float, N s/m
        The touching (light) finger's spring-damper, at natural harmonics.
    reference_force : float, N
        Middle of the model's Helmholtz force range at beta 0.1 and 0.3 m/s.
    bowed_pitch_offset_cents : float, cents
        How far the bowed open string sounds above its first mode.
    torsion_frequency_ratio : float
        Torsional fundamental / transverse fundamental (0: no torsion; :mod:`synth.torsion`).
    torsion_impedance_ratio : float
        Torsional impedance at the string's surface / transverse impedance Z0.
    torsion_q : float
        Quality factor of every torsional mode.
    friction_model : {"hyperbolic", "thermal"}
        Bow friction: the hyperbolic friction curve in the slip speed, or rosin whose
        friction falls as the contact heats (:mod:`synth.modal_kernel`).
    rosin_heat : float, J
        Heat in the contact that lowers the static part of the friction by a factor e.
    rosin_cooling_time : float, s
        Time constant of the contact's cooling.
    rosin_noise : float, s/m
        Bridge force of the rosin's noise per unit friction power while the string slips
        (bow noise; 0 for none).
    """

    name: str
    midi_pitch: int
    tension: float
    length: float
    diameter: float
    linear_density: float
    youngs_modulus: float
    mu_s: float
    mu_d: float
    v0: float
    damping_b1: float
    damping_b2: float
    finger_stiffness: float
    finger_damping: float
    touch_stiffness: float = 0.0
    touch_damping: float = 0.0
    reference_force: float = 1.0
    bowed_pitch_offset_cents: float = 0.0
    torsion_frequency_ratio: float = 0.0
    torsion_impedance_ratio: float = 1.0
    torsion_q: float = 10.0
    friction_model: str = "hyperbolic"
    rosin_heat: float = 1.0e-5
    rosin_cooling_time: float = 3.0e-5
    rosin_noise: float = 0.0

    @property
    def bending_stiffness(self) -> float:
        """EI = E pi d**4 / 64, N m**2."""
        return self.youngs_modulus * math.pi * self.diameter**4 / 64.0

    @property
    def impedance(self) -> float:
        """Characteristic impedance Z0 = sqrt(T rho_L), kg/s."""
        return math.sqrt(self.tension * self.linear_density)

    def mode_frequency(self, n: int) -> float:
        """Frequency of mode ``n`` (1-based) of the open string with stiffness, Hz."""
        k = n * math.pi / self.length
        w2 = (self.tension * k**2 + self.bending_stiffness * k**4) / self.linear_density
        return math.sqrt(w2) / (2.0 * math.pi)

    def nominal_frequency(self, tuning_a4: float = 440.0) -> float:
        """Equal-tempered frequency of :attr:`midi_pitch`, Hz."""
        return tuning_a4 * 2.0 ** ((self.midi_pitch - 69) / 12.0)


@dataclass(frozen=True)
class InstrumentConstants:
    """An instrument: its strings (lowest first), body size and tuning (A4, Hz)."""

    name: str
    strings: tuple[StringConstants, ...]
    body_scale: float
    tuning_a4: float


def tuned(string: StringConstants, frequency: float) -> StringConstants:
    """Return ``string`` with the tension that puts its first mode at ``frequency`` (Hz)."""
    k = math.pi / string.length
    w = 2.0 * math.pi * frequency
    tension = (string.linear_density * w**2 - string.bending_stiffness * k**4) / k**2
    return replace(string, tension=tension)


def _config_path() -> Path:
    return Path(str(resources.files("synth") / "config" / "strings.toml"))


TUNINGS = ("bowed", "first_mode", "published")
#: Keys of ``[defaults]`` that every string takes unless it sets its own.
PER_STRING_DEFAULTS = ("finger_stiffness", "finger_damping", "touch_stiffness",
                       "touch_damping", "damping_b1", "damping_b2",
                       "torsion_frequency_ratio", "torsion_impedance_ratio", "torsion_q",
                       "friction_model", "rosin_heat", "rosin_cooling_time", "rosin_noise")


def _no_facts(entry: dict, where: str, path: str) -> None:
    repeated = sorted(_FACT_KEYS & set(entry))
    if repeated:
        raise SchemaError(f"{where} sets {repeated}: instrument facts are read from "
                          "data_schemas/config/instruments.toml, not from a strings file",
                          source=path)


def _strings(inst: dict, per_string: dict, tuning: str, tuning_a4: float,
             path: str) -> tuple[StringConstants, ...]:
    """The strings of one ``[[instrument]]`` entry: facts + physics, tuned."""
    facts = instrument_facts(inst["name"])
    entries = inst["strings"]
    if len(entries) != facts.n_strings:
        raise SchemaError(f"instrument {facts.name!r} lists {len(entries)} strings, the facts "
                          f"{facts.n_strings}", source=path)
    strings = []
    for i, entry in enumerate(entries):
        _no_facts(entry, f"{facts.name} string {i}", path)
        string = StringConstants(name=facts.string_names[i], midi_pitch=facts.open_strings[i],
                                 length=facts.string_lengths[i], **{**per_string, **entry})
        if tuning != "published":
            offset = string.bowed_pitch_offset_cents if tuning == "bowed" else 0.0
            string = tuned(string, string.nominal_frequency(tuning_a4)
                           * 2.0 ** (-offset / 1200.0))
        strings.append(string)
    return tuple(strings)


@cache
def _load_all(path: str, tuning: str) -> dict[str, InstrumentConstants]:
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    defaults = data.get("defaults", {})
    _no_facts(defaults, "[defaults]", path)
    tuning_a4 = limits().tuning_a4
    per_string = {k: defaults[k] for k in PER_STRING_DEFAULTS if k in defaults}
    out = {}
    for inst in data["instrument"]:
        _no_facts({k: v for k, v in inst.items() if k != "name"}, f"[[instrument]] "
                  f"{inst.get('name')!r}", path)
        facts = instrument_facts(inst["name"])
        out[facts.name] = InstrumentConstants(
            name=facts.name, strings=_strings(inst, per_string, tuning, tuning_a4, path),
            body_scale=facts.body_scale, tuning_a4=tuning_a4)
    return out


def load_instrument(name: str, config: str | Path | None = None, *,
                    tuning: str = "bowed") -> InstrumentConstants:
    """Return the constants of instrument ``name`` (violin, viola or cello).

    Parameters
    ----------
    name : str
        Instrument name.
    config : path-like, optional
        A TOML file in the format of ``synth/config/strings.toml`` (string physics only; the
        facts come from :mod:`data_schemas.instruments`) to use instead.
    tuning : {"bowed", "first_mode", "published"}
        How open strings are tuned: so that the bowed string sounds its nominal pitch
        (default, as a player tunes), so that the first mode does, or not at all.
    """
    if tuning not in TUNINGS:
        raise ParameterError(f"tuning={tuning!r} is unknown; choose one of {TUNINGS}")
    table = _load_all(str(config or _config_path()), tuning)
    if name not in table:
        raise ParameterError(f"instrument={name!r} is unknown; choose one of {sorted(table)}")
    return table[name]


def reference_forces(name: str) -> np.ndarray:
    """Reference force of each string of instrument ``name``: the middle of its window, N.

    Each string's playable window differs (the cello C string needs about 10x the violin
    D's force); its ``reference_force`` is the middle of its Helmholtz range at beta 0.1 and
    0.3 m/s as measured on the instrument model (``synth/config/strings.toml``). Gesture
    sampling moves sampled forces into each string's window with it; the rules play their
    own newton table (:func:`pipelines.perform.config.bow_force`).

    Returns
    -------
    np.ndarray [shape=(n_strings,)], N
        Reference forces, lowest string first.

    Examples
    --------
    >>> reference_forces("violin").tolist()
    [1.5, 1.5, 0.541, 0.541]
    """
    import numpy as np  # here: the CLI's --help imports this module and stays light

    return np.array([s.reference_force for s in load_instrument(name).strings])


__all__ = ["INSTRUMENT_NAMES", "TUNINGS", "InstrumentConstants", "StringConstants",
           "load_instrument", "reference_forces", "tuned"]
