"""A simulated recording session: performers play scripts, one recording file per take.

No public bowing data set can be had offline, so the database is trained and tested on
recordings from simulated violinists, violists and cellists (each on its instrument's
strings, string lengths and bow, :mod:`data_schemas.instruments`, with per-string forces
given by the caller): :func:`gesture_db.script.recording_script` writes the
scripts, :func:`gesture_db.playing.play_script` plays them in a performer's style
(:mod:`gesture_db.simulate_config`), and :func:`simulate_recordings` writes each take's
recording and annotation (the ground truth).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from data_schemas.annotation import write_annotation
from data_schemas.errors import ParameterError
from data_schemas.recording import RECORDING_FRAME_RATE, check_instrument, write_recording
from gesture_db.playing import play_script
from gesture_db.script import recording_script
from gesture_db.simulate_config import PERFORMERS, Performer, make_performers


def simulate_recordings(n_notes: int, n_performers: int, out_dir: str | Path, *, seed: int = 0,
                        notes_per_take: int = 500,
                        frame_rate: float = RECORDING_FRAME_RATE,
                        performers: Sequence[Performer] | None = None,
                        instrument: str = "violin",
                        force_factors: Sequence[float] | None = None,
                        progress: bool = False) -> list[Path]:
    """Simulate a recording session and write one recording + annotation per take.

    Parameters
    ----------
    n_notes : int
        Total number of notes over all performers.
    n_performers : int
        Number of performer styles (see :func:`gesture_db.simulate_config.make_performers`).
    out_dir : path-like
        Output directory; takes are ``<performer>_take<k>.parquet`` with
        ``<performer>_take<k>.annotation.parquet`` beside them.
    seed : int
        Seed of the :class:`numpy.random.Generator`.
    notes_per_take : int
        Notes per take file.
    frame_rate : float
        Frames per second (200-240 Hz).
    performers : sequence of Performer, optional
        Base styles (default :data:`gesture_db.simulate_config.PERFORMERS`; see
        :func:`gesture_db.simulate_config.load_performers`).
    instrument : {"violin", "viola", "cello"}
        Instrument played (written to each recording's metadata; takes of a viola or cello
        are named ``<instrument>-<performer>_take<k>``).
    force_factors : sequence of 4 float, optional
        Per string, the performer's force relative to the violinist's dynamics table
        (``pipelines.cli.commands.simulate_recordings.string_forces`` derives them from the
        instrument model's reference forces); default all 1.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    list of pathlib.Path
        The recording files written.
    """
    factors = _check(n_notes, n_performers, notes_per_take, frame_rate, instrument,
                     force_factors)
    rng = np.random.default_rng(seed)
    bases = PERFORMERS if performers is None else tuple(performers)
    if not bases:
        raise ParameterError("performers must hold at least one style")
    styles = make_performers(n_performers, rng, bases)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    per = [n_notes // n_performers + (1 if k < n_notes % n_performers else 0)
           for k in range(n_performers)]
    jobs = []
    for perf, count in zip(styles, per, strict=True):
        take = 0
        while count > 0:
            size = min(notes_per_take, count)
            jobs.append((perf, take, size))
            count -= size
            take += 1
    seeds = rng.integers(0, 2**63 - 1, len(jobs))
    paths = []
    from tqdm import tqdm

    for (perf, take, size), job_seed in tqdm(list(zip(jobs, seeds, strict=True)),
                                             desc="simulate", unit="take",
                                             disable=not progress):
        job_rng = np.random.default_rng(int(job_seed))
        prefix = "" if instrument == "violin" else f"{instrument}-"
        rid = f"{prefix}{perf.name}_take{take:03d}"
        script = recording_script(size, job_rng, instrument)
        recording, annotation = play_script(script, perf, job_rng, frame_rate=frame_rate,
                                            recording_id=rid, force_factors=factors)
        path = out / f"{rid}.parquet"
        write_annotation(annotation, out / f"{rid}.annotation.parquet")
        write_recording(recording, path, instrument=instrument)
        paths.append(path)
    return paths


def _check(n_notes: int, n_performers: int, notes_per_take: int, frame_rate: float,
           instrument: str, force_factors: Sequence[float] | None) -> np.ndarray | None:
    """Refuse bad arguments of :func:`simulate_recordings`; the force factors as an array."""
    if n_notes < 1 or n_performers < 1 or notes_per_take < 1:
        raise ParameterError(f"n_notes={n_notes}, n_performers={n_performers} and "
                             f"notes_per_take={notes_per_take} must be >= 1")
    if not 200.0 <= frame_rate <= 240.0:
        raise ParameterError(f"frame_rate={frame_rate} Hz is outside 200-240 Hz")
    check_instrument(instrument, "simulate_recordings")
    factors = None if force_factors is None else np.asarray(force_factors, float)
    if factors is not None and (factors.shape != (4,) or not np.all(np.isfinite(factors))
                                or np.any(factors <= 0)):
        raise ParameterError(f"force_factors={force_factors} must be 4 positive numbers")
    return factors


__all__ = ["simulate_recordings"]
