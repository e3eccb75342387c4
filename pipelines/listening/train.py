"""The training job: every string x dynamic pair of an instrument, in parallel, resumable.

Each pair (:func:`train_one`) runs basic training with the chosen teacher, fits its
classifier, searches K and the initial forces, and writes ``<instrument>-<s>-<dyn>.npz`` (arrays),
its JSON metadata (``"complete": true`` last) and the pair's judged clips as a labels table
``labels/<key>.parquet``. A rerun skips complete pairs, so an interrupted run resumes.
Pairs run on local worker processes, or on a dask.distributed cluster given its address.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from data_schemas.io import remove_stale_temps
from data_schemas.labels import AUTO_LABELLER, merge_labels, read_labels, write_labels
from synth.listening.basic_training import JudgedClip
from synth.listening.classifier import DYNAMICS, MODEL_FORMAT, pair_key, save_pair
from synth.listening.training_settings import DEFAULT_LANES, TrainingSettings

TEACHERS = ("auto", "human", "both")


def clip_id(key: str, semitones: float, force: float) -> str:
    """Stable id of an automatic training clip."""
    return f"{key}-s{semitones:g}-F{force:.5g}"


def pair_seed(seed: int, string: int, dynamic: str) -> int:
    """Seed of one pair's training from the run's ``seed`` (pairs differ, runs repeat)."""
    return seed * 1009 + string * 17 + DYNAMICS.index(dynamic)


def is_complete(out_dir: str | os.PathLike, key: str, labels_sha256: str | None = None,
                lane: tuple[float, float] | None = None) -> bool:
    """Whether a pair finished training in this model format (its JSON says ``complete``).

    A pair of an older format (the pickled ``.joblib`` models) is not complete: a rerun
    trains it again in the current format. With ``labels_sha256`` (see
    :func:`labels_digest`) a pair trained from other labels is not complete either, nor,
    with ``lane`` (bow velocity m/s, beta), one trained at another bow lane (its JSON's
    ``velocity`` and ``beta``): the rules' lanes moved, so its clips were played elsewhere.
    """
    import json

    path = Path(out_dir) / f"{key}.json"
    try:
        meta = json.loads(path.read_text("utf-8"))
        done = bool(meta.get("complete")) and meta.get("format") == MODEL_FORMAT
        if done and lane is not None:
            done = bool(np.allclose([meta["velocity"], meta["beta"]], lane, rtol=1e-9,
                                    atol=0.0))
    except (OSError, ValueError, AttributeError, KeyError, TypeError):
        return False
    if not done or labels_sha256 is None:
        return done
    trained = meta.get("labels_sha256", "auto" if meta.get("teacher") == "auto" else None)
    return trained == labels_sha256


def _human_rows(labels: pd.DataFrame | None, instrument: str, string: int,
                dynamic: str) -> pd.DataFrame | None:
    if labels is None:
        return None
    return labels[(labels["instrument"] == instrument) & (labels["string"] == string)
                  & (labels["dynamic"] == dynamic) & (labels["labeller"] != AUTO_LABELLER)]


def labels_digest(teacher: str, labels: pd.DataFrame | None, instrument: str, string: int,
                  dynamic: str) -> str:
    """What a pair is trained from: ``"auto"``, or the SHA-256 of its human label rows.

    Recorded in the pair's metadata, so new labels make a finished pair stale.

    Examples
    --------
    >>> labels_digest("auto", None, "violin", 1, "mf")
    'auto'
    """
    if teacher == "auto":
        return "auto"
    import hashlib

    rows = _human_rows(labels, instrument, string, dynamic)
    text = "" if rows is None else rows.drop(columns=["time"], errors="ignore").sort_values(
        ["clip_id", "labeller"], kind="stable").to_csv(index=False)
    return hashlib.sha256(f"{teacher}\n{text}".encode()).hexdigest()


def _labels_frame(clips: list[JudgedClip], key: str, dynamic: str) -> pd.DataFrame:
    now = pd.Timestamp.now(tz="UTC").floor("s")
    return pd.DataFrame({
        "clip_id": [clip_id(key, j.clip.spec.semitones, j.force) for j in clips],
        "audio_path": [None] * len(clips),
        "instrument": [j.clip.spec.instrument for j in clips],
        "string": [j.clip.spec.string for j in clips],
        "dynamic": dynamic,
        "finger_semitones": [j.clip.spec.semitones for j in clips],
        "bow_force": [j.force for j in clips],
        "bow_velocity": [j.clip.spec.bow_velocity for j in clips],
        "beta": [j.clip.spec.beta for j in clips],
        "label": [j.label for j in clips],
        "labeller": AUTO_LABELLER,
        "time": now,
    })


def _human_clips(human: pd.DataFrame, base: Path) -> list[JudgedClip]:
    """Clips of human labels: the labelled audio, or re-rendered from the settings."""
    import soundfile

    from synth.listening.clips import Clip, ClipSpec, render_clip

    out = []
    for row in human.itertuples(index=False):
        spec = ClipSpec(row.instrument, int(row.string), float(row.finger_semitones),
                        float(row.bow_force), float(row.bow_velocity), float(row.beta))
        if isinstance(row.audio_path, str) and row.audio_path:
            path = Path(row.audio_path)
            path = path if path.is_absolute() else base / path
            try:
                audio, sr = soundfile.read(str(path), dtype="float32")
            except (OSError, RuntimeError) as exc:
                raise ParameterError(f"labels: clip {row.clip_id}: cannot read audio "
                                     f"{path} ({str(exc).splitlines()[0]})") from None
            audio = audio if audio.ndim == 1 else audio.mean(axis=1)
            n = min(audio.size, int(0.3 * sr))
            clip = Clip(spec, audio, np.zeros(n), np.zeros(0), int(sr))
        else:
            clip = render_clip(spec, context=0.1)
        out.append(JudgedClip(clip, int(row.label)))
    return out


def train_one(instrument: str, string: int, dynamic: str, out_dir: str, *,
              teacher: str = "auto", labels: pd.DataFrame | None = None,
              labels_base: str = ".", lane: tuple[float, float] | None = None,
              settings: TrainingSettings | None = None, seed: int = 0) -> dict[str, Any]:
    """Train one pair and write its files; return a summary (key, accuracy, K, forces, s).

    Parameters
    ----------
    instrument, string, dynamic
        The pair.
    out_dir : str
        Model directory.
    teacher : {"auto", "human", "both"}
    labels : pandas.DataFrame, optional
        Human labels (labels table) for ``human`` / ``both``.
    labels_base : str
        Directory that relative ``audio_path`` values are relative to.
    lane : (float, float), optional
        Bow velocity (m/s) and beta of the dynamic.
    settings : TrainingSettings, optional
    seed : int
    """
    from synth.listening.basic_training import basic_training
    from synth.listening.training import train_pair

    start = time.perf_counter()
    key = pair_key(instrument, string, dynamic)
    settings = settings or TrainingSettings()
    seed = pair_seed(seed, string, dynamic)
    human = _human_rows(labels, instrument, string, dynamic) if teacher != "auto" else None
    clips: list[JudgedClip] = []
    frame = None
    if teacher in ("auto", "both"):
        clips = basic_training(instrument, string, dynamic, lane=lane, settings=settings,
                               seed=seed)
        frame = _labels_frame(clips, key, dynamic)
    if human is not None and len(human):
        merged = merge_labels(frame, human)
        by_id = dict(zip(merged["clip_id"], merged["label"], strict=True))
        if frame is not None:
            for j, cid in zip(clips, frame["clip_id"], strict=True):
                label = int(by_id.get(cid, j.label))
                if label != j.label:  # a human's judgement replaces the teacher's hop labels
                    j.label, j.hop_labels = label, None
        known = set(frame["clip_id"]) if frame is not None else set()
        extra = human[~human["clip_id"].isin(known)]
        clips = clips + _human_clips(extra, Path(labels_base))
        frame = merged
    if not clips:
        raise ParameterError(f"{key}: no labelled clips (teacher={teacher!r}; give --labels "
                             "with human labels of this pair or use --teacher auto)")
    model, clips = train_pair(instrument, string, dynamic, lane=lane, settings=settings,
                              clips=clips, seed=seed)
    out = Path(out_dir)
    write_labels(frame, out / "labels" / f"{key}.parquet")
    seconds = time.perf_counter() - start
    model.metadata.update(teacher=teacher, train_seconds=seconds,
                          labels_sha256=labels_digest(teacher, labels, instrument, string,
                                                      dynamic),
                          settings={k: v for k, v in asdict(settings).items()
                                    if k not in ("controller", "thresholds")})
    save_pair(model, out)
    from synth.listening.classifier import update_metadata

    update_metadata(out, key, complete=True)
    return {"key": key, "cv_accuracy": model.metadata["cv_accuracy"], "K": model.K,
            "initial_forces": model.metadata["initial_forces"],
            "n_clips": model.metadata["n_clips"], "seconds": seconds}


def _job(args: tuple) -> dict[str, Any]:
    instrument, string, dynamic, out_dir, kwargs = args
    return train_one(instrument, string, dynamic, out_dir, **kwargs)


def train_instrument(instrument: str, out_dir: str | os.PathLike, *, teacher: str = "auto",
                     labels_path: str | os.PathLike | None = None,
                     pairs: Sequence[tuple[int, str]] | None = None,
                     lanes: dict[str, tuple[float, float]] | None = None,
                     settings: TrainingSettings | None = None, workers: int | None = None,
                     scheduler: str | None = None, seed: int = 0, progress: bool = True,
                     on_result: Callable[[dict], None] | None = None) -> list[dict[str, Any]]:
    """Train every (or the given) string x dynamic pair of an instrument.

    Parameters
    ----------
    instrument : str
    out_dir : path-like
        Model directory (created); complete pairs already there are skipped.
    teacher : {"auto", "human", "both"}
    labels_path : path-like, optional
        Human labels (Parquet/CSV labels table); required for ``human``.
    pairs : sequence of (int, str), optional
        Subset of (string, dynamic) pairs.
    lanes : dict, optional
        Dynamic -> (velocity m/s, beta); default :data:`DEFAULT_LANES`.
    settings : TrainingSettings, optional
    workers : int, optional
        Local worker processes (default: CPU count; 1 runs in this process).
    scheduler : str, optional
        Address of a dask.distributed scheduler; pairs then run on its workers.
    seed : int
    progress : bool
        Show a progress bar.
    on_result : callable, optional
        Called with each finished pair's summary.

    Returns
    -------
    list of dict
        Summaries of the pairs trained in this run (skipped pairs are not listed).
    """
    from tqdm import tqdm

    pairs, labels = _checked_request(instrument, teacher, labels_path, pairs)
    lanes = lanes or DEFAULT_LANES
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    remove_stale_temps(out, recursive=True)
    todo = [(s, d) for s, d in pairs if not is_complete(
        out, pair_key(instrument, s, d), labels_digest(teacher, labels, instrument, s, d),
        tuple(lanes[d]))]
    kwargs = {"teacher": teacher, "labels": labels,
              "labels_base": str(Path(labels_path).parent) if labels_path else ".",
              "settings": settings, "seed": seed}
    jobs = [(instrument, s, d, str(out), {**kwargs, "lane": tuple(lanes[d])}) for s, d in todo]
    results: list[dict[str, Any]] = []
    bar = tqdm(total=len(jobs), desc=f"train {instrument}", unit="pair", disable=not progress)

    def done(result: dict[str, Any]) -> None:
        results.append(result)
        bar.set_postfix_str(f"{result['key']} cv {100 * result['cv_accuracy']:.1f} %")
        bar.update(1)
        if on_result is not None:
            on_result(result)

    try:
        _run_jobs(jobs, workers, scheduler, done)
    finally:
        bar.close()
    collect_labels(out)
    return results


def _checked_request(instrument: str, teacher: str, labels_path: str | os.PathLike | None,
                     pairs: Sequence[tuple[int, str]] | None,
                     ) -> tuple[list[tuple[int, str]], pd.DataFrame | None]:
    """The pairs to train (all by default) and the human labels, checked.

    Raises
    ------
    ParameterError
        An unknown teacher, a human teacher without labels, or a pair the instrument lacks.
    """
    from synth.strings import load_instrument

    if teacher not in TEACHERS:
        raise ParameterError(f"--teacher {teacher!r} must be one of {TEACHERS}")
    n_strings = len(load_instrument(instrument).strings)
    labels = None
    if labels_path is not None:
        labels = read_labels(labels_path)
        if labels.empty:
            raise ParameterError(f"{labels_path}: the labels table has no rows")
    elif teacher != "auto":
        raise ParameterError(f"--teacher {teacher} needs --labels LABELS.parquet")
    pairs = list(pairs) if pairs is not None else [(s, d) for s in range(n_strings)
                                                   for d in DYNAMICS]
    for s, d in pairs:
        if not 0 <= s < n_strings or d not in DYNAMICS:
            raise ParameterError(f"pair ({s}, {d!r}) is not a string x dynamic of the "
                                 f"{instrument} (strings 0..{n_strings - 1}, {DYNAMICS})")
    return pairs, labels


def _run_jobs(jobs: list[tuple], workers: int | None, scheduler: str | None,
              done: Callable[[dict], None]) -> None:
    """Run the pair jobs on a dask cluster, in this process or on local workers."""
    if scheduler:
        _run_dask(jobs, scheduler, done)
    elif (workers or os.cpu_count() or 1) <= 1 or len(jobs) <= 1:
        for job in jobs:
            done(_job(job))
    else:
        _run_pool(jobs, int(workers or os.cpu_count() or 1), done)


def _run_pool(jobs: list[tuple], workers: int, done: Callable[[dict], None]) -> None:
    from concurrent.futures import as_completed

    from data_schemas.workers import process_pool

    with process_pool(min(workers, len(jobs)), context="spawn") as pool:
        futures = [pool.submit(_job, job) for job in jobs]
        for future in as_completed(futures):
            done(future.result())


def _run_dask(jobs: list[tuple], scheduler: str, done: Callable[[dict], None]) -> None:
    from distributed import Client, as_completed

    try:
        client = Client(scheduler, timeout="10s")
    except OSError as exc:
        raise ParameterError(f"--scheduler {scheduler}: cannot connect "
                             f"({str(exc).splitlines()[0]})") from None
    try:
        futures = client.map(_job, jobs, pure=False)
        for future in as_completed(futures):
            done(future.result())
    finally:
        client.close()


def collect_labels(out_dir: str | os.PathLike) -> Path | None:
    """Concatenate every pair's ``labels/<key>.parquet`` into ``labels.parquet``."""
    out = Path(out_dir)
    files = sorted((out / "labels").glob("*.parquet"))
    if not files:
        return None
    frame = pd.concat([read_labels(f) for f in files], ignore_index=True)
    return write_labels(frame, out / "labels.parquet")
