"""Actions table -> audio on any registered engine (default: the modal model).

How the modal engine reads the table (interpolation between rows, lifted bows, plucks) is
described in :mod:`synth.tracks`.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from synth.engines import DEFAULT_ENGINE, Engine, get_engine
from synth.tracks import DEFAULT_TAIL

#: A render louder than this (times full scale) is an error, not a file: bowing in the
#: documented ranges peaks below about 6x and playing below 1.
AUDIO_CEILING = 16.0


def _engine(instrument: str | Engine, engine: str, sample_rate: int, seed: int,
            options: dict[str, Any]) -> Engine:
    if not isinstance(instrument, str):
        return instrument
    return get_engine(engine, instrument, sample_rate=sample_rate, seed=seed, **options)


def render_actions(
    actions: pd.DataFrame,
    *,
    instrument: str | Engine = "violin",
    engine: str = DEFAULT_ENGINE,
    sample_rate: int = 44100,
    seed: int = 0,
    oversample: int | None = None,
    body: str | os.PathLike | np.ndarray | None = "synthesized",
    body_seed: int = 0,
    tail: float = DEFAULT_TAIL,
    progress: bool = False,
    max_duration: float | None = None,
    source: str = "<actions>",
) -> np.ndarray:
    """Render an actions table to mono audio.

    Parameters
    ----------
    actions : pandas.DataFrame
        An actions table (validated here; see :data:`data_schemas.ACTIONS`).
    instrument : {"violin", "viola", "cello"} or Engine
        The instrument: a name (a fresh engine is built from it, the seed and settings) or
        an engine to play on from its current state.
    engine : str
        Registered engine to build from a name (:func:`synth.engines.engine_names`).
    sample_rate : {44100, 48000}, Hz
    seed : int
        Seed of the friction noise; the same actions and seed give identical audio.
    oversample : {1, 2, 4}, optional
        Internal oversampling of the modal engine (default 2).
    body : "synthesized", path-like, np.ndarray or None
        Body impulse response of the modal engine.
    body_seed : int
        Which synthesized body (see :class:`synth.Instrument`).
    tail : float, s
        Ring-out rendered after the last row.
    progress : bool
        Show a progress bar.
    max_duration : float, optional, s
        Longest audio allowed, last row plus ``tail`` (default
        :data:`data_schemas.limits.LIMITS`); checked before anything is allocated.
    source : str
        The table's file, named in errors.

    Returns
    -------
    np.ndarray [shape=(n,)], float32

    Examples
    --------
    >>> import pandas as pd
    >>> actions = pd.DataFrame({"time": [0.0, 0.5], "string": [1, 1],
    ...     "finger_ratio": [0.0, 0.0], "bow_force": [1.0, 1.0], "bow_velocity": [0.3, 0.3],
    ...     "beta": [0.1, 0.1], "bow_position": [0.2, 0.5], "pluck": [False, False]})
    >>> audio = render_actions(actions, instrument="violin", seed=0, tail=0.1)
    >>> audio.dtype, audio.size / 44100 >= 0.6
    (dtype('float32'), True)
    """
    return render_with_diagnostics(actions, instrument=instrument, engine=engine,
                                   sample_rate=sample_rate, seed=seed, oversample=oversample,
                                   body=body, body_seed=body_seed, tail=tail,
                                   progress=progress, diagnostics=False,
                                   max_duration=max_duration, source=source)[0]


def render_with_diagnostics(
    actions: pd.DataFrame,
    *,
    instrument: str | Engine = "violin",
    engine: str = DEFAULT_ENGINE,
    sample_rate: int = 44100,
    seed: int = 0,
    oversample: int | None = None,
    body: str | os.PathLike | np.ndarray | None = "synthesized",
    body_seed: int = 0,
    tail: float = DEFAULT_TAIL,
    progress: bool = False,
    diagnostics: bool = True,
    max_duration: float | None = None,
    source: str = "<actions>",
) -> tuple[np.ndarray, pd.DataFrame | None]:
    """Render like :func:`render_actions` and also return per-hop contact diagnostics.

    Returns
    -------
    audio : np.ndarray [shape=(n,)], float32
    diagnostics : pandas.DataFrame or None
        One row per hop of 256 samples per excited string (table
        :data:`data_schemas.CONTACT_DIAGNOSTICS`), or None when not asked for or when the
        engine cannot measure them.
    """
    check_length(actions, tail, source, max_duration)
    options = {"oversample": oversample, "body": body, "body_seed": body_seed}
    inst = _engine(instrument, engine, sample_rate, seed, options)
    audio, table = inst.render(actions, tail=tail, progress=progress,
                               diagnostics=diagnostics and inst.has_diagnostics)
    check_audio(audio, sample_rate=inst.sample_rate)
    return audio, table


def check_length(actions: pd.DataFrame, tail: float, source: str = "<actions>",
                 max_duration: float | None = None) -> None:
    """Refuse an actions table whose last row plus ``tail`` is longer than allowed.

    Raises
    ------
    ParameterError
        Naming ``source`` and the option that raises the limit.

    Examples
    --------
    >>> check_length(pd.DataFrame({"time": [0.0, 2.0]}), tail=1.0)
    >>> check_length(pd.DataFrame({"time": [0.0, 1e9]}), 1.0, "a.csv")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: a.csv: the performance lasts 1e+09 s, over the limit...
    """
    from data_schemas.limits import check_duration

    if not len(actions) or "time" not in actions:
        return
    times = pd.to_numeric(actions["time"], errors="coerce").to_numpy(np.float64)
    times = times[np.isfinite(times)]  # text, NaN and inf are the table check's to report
    if times.size:
        check_duration(float(times.max()) + float(tail), source, max_duration)


def check_audio(audio: np.ndarray, ceiling: float = AUDIO_CEILING, *,
                sample_rate: int = 44100) -> None:
    """Refuse audio that is not finite or peaks above ``ceiling`` (full scale = 1).

    Raises
    ------
    ParameterError
        With the sample and its time, so a bad actions table never becomes a file.

    Examples
    --------
    >>> check_audio(np.array([0.0, 0.5, -0.9], np.float32))
    >>> check_audio(np.array([0.0, 0.1, 20.0]))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: the audio peaks at 20 x full scale ...
    """
    step = 1 << 20  # a chunk at a time: no full-length temporaries
    chunks = [audio[a:a + step] for a in range(0, audio.size, step)]
    for k, chunk in enumerate(chunks):
        bad = ~np.isfinite(chunk)
        if bad.any():
            first = k * step + int(np.flatnonzero(bad)[0])
            raise ParameterError(f"the audio is not finite from sample {first} "
                                 f"({first / sample_rate:.3f} s at {sample_rate} Hz)")
    peak = max((float(np.max(np.abs(c))) for c in chunks), default=0.0)
    if peak > ceiling:
        first = next(k * step + int(np.flatnonzero(np.abs(c) > ceiling)[0])
                     for k, c in enumerate(chunks) if np.max(np.abs(c)) > ceiling)
        raise ParameterError(f"the audio peaks at {peak:.3g} x full scale (ceiling "
                             f"{ceiling:g}) from sample {first}: check the actions' forces and "
                             "beta")
