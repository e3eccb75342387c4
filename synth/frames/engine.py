"""``FramesEngine``: an actions table played with frames of real recordings.

Registered as engine ``"frames"`` (:mod:`synth.engines`). It needs an audio-frame database
(``arco build-db --audio DIR -o DB``; option ``audio_db``: its path or an
:class:`~data_schemas.audio_frames.AudioDatabase`). It renders whole actions tables only:
the search looks at the whole performance, so :meth:`FramesEngine.process` refuses.
"""

from __future__ import annotations

import os
import time
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.audio_frames import AudioDatabase, read_audio_database
from data_schemas.errors import ParameterError
from synth.frames.index import candidates, frame_midi, load_index, raw_features
from synth.frames.ola import Grain, overlap_add
from synth.frames.targets import PitchProfile, derive_targets
from synth.frames.viterbi_kernel import viterbi_frames

#: Cost of a join that is not a frame's own successor (whitened feature units).
JOIN_PENALTY = 1.0
#: Weight of the concatenation cost against the target cost.
JOIN_WEIGHT = 1.0


class FramesEngine:
    """Frame-concatenative synthesis from an audio-frame database.

    Parameters
    ----------
    instrument : str
        Instrument whose strings the actions play (the database should hold its sound).
    sample_rate : int, Hz
    seed : int
        Seed of the database's k-means when its index is first built (the render itself
        has no random process).
    audio_db : path-like or AudioDatabase
        The database (required).
    **options
        Options of other engines (``body``, ``oversample`` ...) are ignored.

    Raises
    ------
    ParameterError
        No ``audio_db``.
    """

    has_diagnostics = False

    def __init__(self, instrument: str = "violin", *, sample_rate: int = 44100, seed: int = 0,
                 audio_db: str | os.PathLike | AudioDatabase | None = None,
                 **options: Any) -> None:
        from data_schemas.instruments import instrument_facts

        if audio_db is None:
            raise ParameterError("engine 'frames' needs an audio-frame database: "
                                 "--audio-db DB (arco build-db --audio DIR -o DB)")
        self.name = instrument
        self.n_strings = instrument_facts(instrument).n_strings
        self.sample_rate = int(sample_rate)
        self.seed = int(seed)
        self.db = audio_db if isinstance(audio_db, AudioDatabase) else read_audio_database(
            audio_db)
        self.index = load_index(self.db, seed=0)
        f = self.db.frames
        rows = self.index.rows
        self._midi = frame_midi(f)[rows]
        self._energy = f["energy_db"].to_numpy(np.float64)[rows]
        self._profile = PitchProfile.of(self._midi, self._energy,
                                        f["centroid_hz"].to_numpy(np.float64)[rows])
        self._audio: dict[str, np.ndarray] = {}
        #: Output samples between frames (the database's hop at this rate).
        self.hop = int(round(self.db.hop_s * self.sample_rate))
        #: Seconds of the last render's search (targets, candidates, Viterbi).
        self.search_seconds = 0.0

    def reset(self) -> None:
        """Nothing to bring to rest (each render starts afresh)."""

    def process(self, n_samples: int, controls=None, *, plucks=(), diagnostics: bool = True):
        """Not available: the search needs the whole performance.

        Raises
        ------
        ParameterError
            Always.
        """
        raise ParameterError("engine 'frames' renders whole actions tables only (render, "
                             "arco render/synth); it has no block mode")

    def search(self, actions: pd.DataFrame, tail: float = 0.0,
               reference: tuple[float, ...] = ()) -> tuple[np.ndarray, np.ndarray, Any]:
        """Targets and the chosen candidate (index into the frame index, -1 silent) per frame.

        ``reference``: :func:`synth.frames.targets.derive_targets`'s (default: the table's).

        Returns
        -------
        chosen : np.ndarray, int64
        sounding : np.ndarray, bool
        targets : synth.frames.targets.Targets
        """
        tg = derive_targets(actions, self.name, self.hop / self.sample_rate, self._profile,
                            tail=tail, reference=reference)
        chosen = np.full(tg.times.size, -1, np.int64)
        on = np.flatnonzero(tg.sounding)
        if on.size == 0:
            return chosen, tg.sounding, tg
        midi = 69 + 12 * np.log2(tg.f0[on] / 440.0)
        t = raw_features(midi, tg.energy_db[on], tg.centroid_hz[on]) @ self.index.whiten
        cand, cost = candidates(self.index, t)
        succ = self.index.successor
        feats = self.index.features * JOIN_WEIGHT
        for seg in np.split(np.arange(on.size), np.flatnonzero(np.diff(on) > 1) + 1):
            path, _ = viterbi_frames(cand[seg], cost[seg], feats, succ, JOIN_PENALTY)
            chosen[on[seg]] = cand[seg][np.arange(seg.size), path]
        return chosen, tg.sounding, tg

    def _recording(self, name: str) -> np.ndarray:
        if name not in self._audio:
            self._audio[name] = self.db.load_audio(name).astype(np.float64)
        return self._audio[name]

    def render(self, actions: pd.DataFrame, *, tail: float = 0.5, progress: bool = False,
               diagnostics: bool = False) -> tuple[np.ndarray, None]:
        """Play a whole actions table.

        Where several strings are bowed at once (a double stop or chord) each string is a
        voice of its own (:func:`synth.voices.voice_rows`), searched and overlap-added
        alone, and the voices are mixed.

        Returns
        -------
        audio : np.ndarray, float32
            ``(last row time + tail) * sample_rate`` samples.
        diagnostics : None
            The engine cannot measure contact diagnostics.
        """
        from data_schemas.actions import validate_actions
        from synth.voices import voice_count, voice_rows

        actions = validate_actions(actions)
        self.search_seconds = 0.0
        if not len(actions):
            return np.zeros(0, np.float32), None
        end = float(actions["time"].max())
        n = int(round((end + tail) * self.sample_rate))
        n_voices = voice_count(actions)
        parts = [actions] if n_voices <= 1 else [voice_rows(actions, v, self.name)
                                                 for v in range(n_voices)]
        # every voice's level and brightness relative to the whole table's loudest strings
        ref = () if n_voices <= 1 else derive_targets(
            actions, self.name, self.hop / self.sample_rate, self._profile).reference
        out = np.zeros(n)
        for k, part in enumerate(parts):
            # every voice's grid runs to the table's end + tail
            extra = tail if part is actions else end + tail - float(part["time"].max())
            y = self._play(part, extra, progress and k == 0, ref)[:n]
            out[:y.size] += y
        return out.astype(np.float32), None

    def _play(self, actions: pd.DataFrame, tail: float, progress: bool,
              reference: tuple[float, ...] = ()) -> np.ndarray:
        """One voice: search, then pitch-synchronous overlap-add (float64, unpadded)."""
        start = time.perf_counter()
        chosen, sounding, tg = self.search(actions, tail, reference)
        self.search_seconds += time.perf_counter() - start
        frames = self.db.frames
        rows = self.index.rows
        rec = frames["recording"].to_numpy()
        tsec = frames["time_s"].to_numpy(np.float64)
        grains: list[Grain | None] = []
        prev = -2
        for c in chosen:
            if c < 0:
                grains.append(None)
                prev = -2
                continue
            r = rows[c]
            f0 = float(440.0 * 2 ** ((self._midi[c] - 69) / 12))
            grains.append(Grain(self._recording(str(rec[r])), tsec[r] * self.db.sample_rate,
                                f0, float(self._energy[c]),
                                prev >= 0 and self.index.successor[prev] == c))
            prev = c
        return overlap_add(grains, tg.f0, tg.energy_db, self.hop, self.db.sample_rate,
                           self.sample_rate, progress=progress)


__all__ = ["FramesEngine"]
