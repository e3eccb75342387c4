"""One interface for every synthesis engine ("controls in, audio out") and a registry by name.

An engine is an instrument that turns bowing controls into audio in one of two ways:

- **block processing** for the listening loop, :meth:`Engine.process`: the engine keeps its
  state and advances by ``n_samples`` output samples under the given per-string controls,
  returning a :class:`~synth.instrument.Block` (audio, and contact diagnostics when the
  engine can measure them and they are asked for);
- **a whole actions table**, :meth:`Engine.render`: actions table -> audio (and optionally a
  per-hop contact-diagnostics table, :data:`data_schemas.CONTACT_DIAGNOSTICS`).

Engines are found by name through :func:`get_engine`; :func:`engine_names` lists them. The
modal bowed-string model (:class:`synth.instrument.Instrument`) is registered as
``"modal"``. Everything in Arco that needs an instrument asks the registry, so a new engine
is one module and one :func:`register_engine` call.

Examples
--------
A minimal engine: silence that still honours the interface.

>>> import numpy as np
>>> from synth.instrument import Block
>>> class Silence:
...     name = "violin"
...     n_strings = 4
...     has_diagnostics = False
...     def __init__(self, instrument="violin", *, sample_rate=44100, seed=0, **options):
...         self.sample_rate = sample_rate
...     def reset(self):
...         pass
...     def process(self, n_samples, controls=None, *, plucks=(), diagnostics=True):
...         z = np.zeros(n_samples, np.float32)
...         return Block(z, z.astype(np.float64), {})
...     def render(self, actions, *, tail=0.5, progress=False, diagnostics=False):
...         n = int((float(actions["time"].max()) + tail) * self.sample_rate)
...         return np.zeros(n, np.float32), None
>>> register_engine("silence", Silence, "no sound at all (an example)")
>>> engine = get_engine("silence", "violin")
>>> isinstance(engine, Engine)
True
>>> engine.process(256, {1: None}).audio.shape
(256,)
>>> "silence" in engine_names() and "modal" in engine_names()
True
>>> unregister_engine("silence")
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from data_schemas.errors import ParameterError

if TYPE_CHECKING:  # pragma: no cover - typing only
    import numpy as np
    import pandas as pd

    from synth.instrument import Block, BowControl

#: Name of the engine used when none is given.
DEFAULT_ENGINE = "modal"


@runtime_checkable
class Engine(Protocol):
    """What every synthesis engine provides.

    Attributes
    ----------
    name : str
        Instrument name (``violin``, ``viola`` or ``cello``).
    sample_rate : int, Hz
        Output sample rate.
    n_strings : int
        Number of strings (0 = lowest).
    has_diagnostics : bool
        Whether :meth:`process` and :meth:`render` can report contact diagnostics (stick/slip
        of the string under the bow); engines built on recorded audio cannot.
    """

    name: str
    sample_rate: int
    n_strings: int
    has_diagnostics: bool

    def reset(self) -> None:
        """Bring the engine to rest (seeded streams go on)."""

    def process(self, n_samples: int, controls: Mapping[int, BowControl | None] | None = None,
                *, plucks: Iterable[int] = (), diagnostics: bool = True) -> Block:
        """Advance by ``n_samples`` output samples under per-string controls."""

    def render(self, actions: pd.DataFrame, *, tail: float = 0.5, progress: bool = False,
               diagnostics: bool = False) -> tuple[np.ndarray, pd.DataFrame | None]:
        """Play a whole actions table: float32 audio and (optionally) diagnostics."""


@dataclass(frozen=True)
class EngineEntry:
    """A registered engine: its name, a factory and a one-line description."""

    name: str
    factory: Callable[..., Engine]
    summary: str


_REGISTRY: dict[str, EngineEntry] = {}


def register_engine(name: str, factory: Callable[..., Engine], summary: str) -> None:
    """Register ``factory(instrument, *, sample_rate, seed, **options)`` as engine ``name``.

    Parameters
    ----------
    name : str
        Engine name used by ``--engine`` and :func:`get_engine`.
    factory : callable
        Builds an :class:`Engine` for an instrument name.
    summary : str
        One line for ``arco engines``.

    Raises
    ------
    ParameterError
        ``name`` is already registered.
    """
    if name in _REGISTRY:
        raise ParameterError(f"engine {name!r} is already registered")
    _REGISTRY[name] = EngineEntry(name, factory, summary)


def unregister_engine(name: str) -> None:
    """Remove engine ``name`` from the registry (no error if it is absent)."""
    _REGISTRY.pop(name, None)


def _modal(instrument: str = "violin", **settings: Any) -> Engine:
    """The modal model, imported when an instrument is first built (not to list engines)."""
    from synth.instrument import Instrument

    return Instrument(instrument, **settings)


def _cws(instrument: str = "violin", **settings: Any) -> Engine:
    """Cluster-weighted sampling, imported when an engine is first built."""
    from synth.cws.engine import CwsEngine

    return CwsEngine(instrument, **settings)


def _frames(instrument: str = "violin", **settings: Any) -> Engine:
    """The frame-concatenation engine, imported when first built."""
    from synth.frames.engine import FramesEngine

    return FramesEngine(instrument, **settings)


def _builtin() -> None:
    if "modal" not in _REGISTRY:
        register_engine("modal", _modal,
                        "modal bowed strings with finger, decimator and body (physical model)")
    if "cws" not in _REGISTRY:
        register_engine("cws", _cws, "cluster-weighted sampling of recorded violin audio "
                        "(needs audio_db; Schoner et al. 2000)")
    if "frames" not in _REGISTRY:
        register_engine("frames", _frames,
                        "frames of real recordings chosen by a Viterbi search and overlap-"
                        "added (needs --audio-db from arco build-db --audio)")


@dataclass(frozen=True)
class EngineChoice:
    """An engine name with its options, passed wherever an engine name is accepted.

    Methods and renderers hand ``engine`` on to :func:`get_engine` untouched, so options an
    engine needs (``frames``, ``cws``: ``audio_db``) travel with the name.

    Examples
    --------
    >>> str(EngineChoice("modal", {"body": None}))
    'modal'
    >>> get_engine(EngineChoice("modal", {"body": None}), "violin").n_strings
    4
    """

    name: str
    options: Mapping[str, Any]

    def __str__(self) -> str:
        return self.name


def engine_names() -> list[str]:
    """Names of the registered engines, the default first.

    Examples
    --------
    >>> engine_names()[0]
    'modal'
    """
    _builtin()
    return sorted(_REGISTRY, key=lambda n: (n != DEFAULT_ENGINE, n))


def describe_engines() -> list[EngineEntry]:
    """Every registered engine with its one-line summary, the default first."""
    return [_REGISTRY[n] for n in engine_names()]


def get_engine(name: str | EngineChoice = DEFAULT_ENGINE, instrument: str = "violin", *,
               sample_rate: int = 44100, seed: int = 0, **options: Any) -> Engine:
    """Build engine ``name`` for ``instrument``.

    Parameters
    ----------
    name : str or EngineChoice
        A registered engine (see :func:`engine_names`), or one with its options (they
        override ``options`` given here).
    instrument : {"violin", "viola", "cello"}
    sample_rate : {44100, 48000}, Hz
    seed : int
        Seed of the engine's random processes (the performance).
    **options
        Engine-specific settings (for ``modal``: ``body``, ``body_seed``, ``oversample``,
        ...; see :class:`synth.instrument.Instrument`).

    Returns
    -------
    Engine

    Raises
    ------
    ParameterError
        Unknown engine name (the message lists the known ones).

    Examples
    --------
    >>> violin = get_engine("modal", "violin", seed=1, body=None)
    >>> violin.name, violin.n_strings
    ('violin', 4)
    """
    if isinstance(name, EngineChoice):
        options = {**options, **name.options}
        name = name.name
    names = engine_names()
    if name not in _REGISTRY:
        raise ParameterError(f"engine={name!r} is not one of {names}")
    return _REGISTRY[name].factory(instrument, sample_rate=sample_rate, seed=seed, **options)
