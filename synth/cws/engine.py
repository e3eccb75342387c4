"""The ``cws`` engine: an actions table played by cluster-weighted sampling of real audio.

Build it with ``synth.get_engine("cws", "violin", seed=0, audio_db=DB)`` (or ``arco render
SCORE --engine cws --audio-db DB``): ``audio_db`` is an audio-frame database object
(``data_schemas.audio_frames.AudioDatabase`` or anything with its attributes ``root``,
``sample_rate``, ``frames``, ``notes`` and ``load_audio``) or a path, read with
``data_schemas.audio_frames.read_audio_database``. The model is trained on first use and
kept in memory per database and settings (training is deterministic: the same database,
``n_clusters`` and seed give the same model).

What it plays: the notes of the actions table (:func:`synth.cws.notes.action_notes`:
pitch from string + finger ratio, volume from bow speed and force, bow changes from the
velocity's sign and bow stops), each by :func:`synth.cws.synthesis.render_notes`. It has no
per-block processing (the listening loop's ``process``) and no contact diagnostics.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from data_schemas.instruments import instrument_facts

_MODELS: dict[tuple, Any] = {}
#: The modal engine's settings, ignored here (see :class:`CwsEngine`).
MODAL_SETTINGS = ("oversample", "body", "body_seed")


def _database(audio_db: Any) -> Any:
    if audio_db is None:
        raise ParameterError("engine 'cws' needs an audio-frame database: audio_db=DB "
                             "(arco render ... --engine cws --audio-db DB)")
    if isinstance(audio_db, str | os.PathLike):
        from data_schemas.audio_frames import read_audio_database

        return read_audio_database(audio_db)
    return audio_db


def _key(db: Any, n_clusters: int, seed: int) -> tuple:
    frames = pd.util.hash_pandas_object(db.frames, index=False).to_numpy()
    notes = pd.util.hash_pandas_object(db.notes, index=False).to_numpy()
    return (str(getattr(db, "root", "")), int(db.sample_rate), n_clusters, seed,
            int(frames.sum(dtype=np.uint64)), int(notes.sum(dtype=np.uint64)), len(frames))


def trained_model(db: Any, *, n_clusters: int = 12, seed: int = 0) -> Any:
    """The cluster-weighted sampler of ``db``, trained once per process and settings."""
    from synth.cws.training import train

    key = _key(db, n_clusters, seed)
    if key not in _MODELS:
        _MODELS[key] = train(db, n_clusters=n_clusters, seed=seed)
    return _MODELS[key]


class CwsEngine:
    """Cluster-weighted sampling of an audio-frame database (Schoner et al. 2000).

    Parameters
    ----------
    instrument : {"violin", "viola", "cello"}
        Whose open strings turn finger ratios into pitch.
    sample_rate : int, Hz
    seed : int
        Seed of EM's start and of the sustain's partial phases.
    audio_db : AudioDatabase-like or path
        The recordings to sample (required).
    n_clusters : int
        Clusters of the model.
    **settings
        Fields of :class:`synth.cws.synthesis.SynthesisSettings` (``attack_s``, ``fade_s``,
        ``onset_fade_s``, ``half_taps``, ``intonation``). The modal engine's settings that
        :func:`synth.render_actions` passes to every engine (``oversample``, ``body``,
        ``body_seed``) are accepted and ignored: the recordings bring their own body.

    Examples
    --------
    >>> try:
    ...     CwsEngine("violin")
    ... except ParameterError as exc:
    ...     print(str(exc)[:52])
    engine 'cws' needs an audio-frame database: audio_db
    """

    has_diagnostics = False

    def __init__(self, instrument: str = "violin", *, sample_rate: int = 44100, seed: int = 0,
                 audio_db: Any = None, n_clusters: int = 12, **settings: Any) -> None:
        from synth.cws.synthesis import SynthesisSettings

        for modal_only in MODAL_SETTINGS:
            settings.pop(modal_only, None)
        self.name = instrument
        self.n_strings = len(instrument_facts(instrument).open_strings)
        self.sample_rate = int(sample_rate)
        self.seed = int(seed)
        try:
            self.settings = SynthesisSettings(**settings)
        except TypeError as exc:
            raise ParameterError(f"engine 'cws': {exc}") from None
        self.db = _database(audio_db)
        self.n_clusters = int(n_clusters)

    @property
    def model(self) -> Any:
        """The trained model (trained on first use)."""
        return trained_model(self.db, n_clusters=self.n_clusters, seed=self.seed)

    def reset(self) -> None:
        """Nothing to reset: every render starts from silence."""

    def process(self, n_samples: int, controls: Any = None, *, plucks: Any = (),
                diagnostics: bool = True) -> Any:
        """Not available: cluster-weighted sampling plays whole notes (use :meth:`render`)."""
        raise ParameterError("engine 'cws' plays whole actions tables only (render), not "
                             "blocks: use it without the listening loop (method rules or "
                             "sampling-open)")

    def search(self, actions: pd.DataFrame, *, tail: float = 1.0
               ) -> list[tuple[pd.DataFrame, list[Any]]]:
        """Per voice its notes and their plans (cluster, sample, pitch, target volume).

        The sustains follow the voice's pitch as the actions play it (vibrato included).

        Each string of a double stop or chord is its own voice (:func:`synth.cws.notes.
        action_notes` with ``voice``); :func:`synth.cws.synthesis.plan_notes` evaluates the
        model for all of a voice's notes at once.
        """
        from data_schemas.actions import validate_actions
        from data_schemas.instruments import semitones_of
        from synth.cws.notes import action_notes, voices
        from synth.cws.synthesis import plan_notes
        from synth.voices import voice_rows

        actions = validate_actions(actions)
        n = self._length(actions, tail)
        out = []
        open_midi = np.asarray(instrument_facts(self.name).open_strings, np.float64)
        for voice in range(max(voices(actions), 1)):
            notes = action_notes(actions, self.name, voice=voice)
            rows = voice_rows(actions, voice, self.name)
            track = (rows["time"].to_numpy(np.float64),
                     open_midi[rows["string"].to_numpy(np.int64)]
                     + semitones_of(rows["finger_ratio"].to_numpy(np.float64)))
            out.append((notes, plan_notes(self.model, notes, n, self.sample_rate,
                                          self.settings, track if len(rows) else None)))
        return out

    def _length(self, actions: pd.DataFrame, tail: float) -> int:
        end = float(actions["time"].max()) if len(actions) else 0.0
        return int(round((end + tail) * self.sample_rate))

    def render(self, actions: pd.DataFrame, *, tail: float = 1.0, progress: bool = False,
               diagnostics: bool = False) -> tuple[np.ndarray, None]:
        """Play a whole actions table; float32 mono audio and no diagnostics.

        The voices of :meth:`search` are synthesized alone and mixed.

        Raises
        ------
        ParameterError
            Diagnostics asked for (this engine has none).
        """
        from synth.cws.synthesis import render_notes

        if diagnostics:
            raise ParameterError("engine 'cws' has no contact diagnostics")
        n = self._length(actions, tail)
        audio = np.zeros(n)
        for voice, (notes, plans) in enumerate(self.search(actions, tail=tail)):
            audio += render_notes(self.model, notes, n, self.sample_rate,
                                  seed=self.seed + voice, settings=self.settings,
                                  progress=progress and voice == 0, plans=plans)
        return audio.astype(np.float32), None


__all__ = ["CwsEngine", "trained_model"]
