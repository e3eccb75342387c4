"""How far is a render from a real violin? Timbre figures of renders beside their recordings.

For each annotated recording (default: the shared Bach Violin Dataset recordings in
``$ARCO_SHARED_DATA/bach-violin``, else ``<repo>/../shared/data/bach-violin``, else
``/work/shared/data/bach-violin``; or ``--recording AUDIO NOTES ALIGNMENT``, repeatable) the
notes of the first ``--seconds`` are played at their aligned times by

- ``rules``: Arco's performance rules (``pipelines.methods.rules.render``, seed 0), from a MIDI
  file whose ticks are milliseconds read back with ``pipelines.score.read_score``;
- ``fluidr3``: the same MIDI file through ``fluidsynth`` and the FluidR3 GM violin (program 41;
  null figures and a reason when fluidsynth is missing);
- ``sawtooth``: an additive band-limited sawtooth per note (the baseline);
- ``feedback`` with ``--models DIR``, ``sampling`` (``sampling-open`` without models) with
  ``--db DB``;
- ``frames``: the rules' actions played by the ``frames`` engine on an audio-frame database
  built once (into a temporary folder) from the recordings, the measured one left out
  (:func:`pipelines.reports.leave_out.without`, shared with ``arco compare --engines``).
  Its extra figures (``frames`` in the report, per recording and mean): database build
  time (of the whole database, once), search and render time, real-time factor, pitch
  error on sustained stretches against the actions' pitch (the rules' source gets the
  same figure), clicks;

and every source, the recording (``real``) included, is measured the same way by
:func:`pipelines.reports.timbre.measure` (44.1 kHz mono, loudness-normalised, up to 14 kHz):
MFCC-frame Frechet distance to the recording, spectral centroid, harmonics 6-10 and 11-20 re
harmonic 1, flatness, harmonic-to-noise, octave-band LTAS (as render minus real), and by
:func:`pipelines.reports.vibrato.vibrato_figures` (YIN pitch of the monophonic notes of at
least 0.31 s: share with vibrato >= 3 cents, extent, rate, intonation spread), and
:func:`pipelines.reports.loudness.level_range_db` (per-note BS.1770 loudness, 10th to 90th
percentile, ``level_range_db``). The
``real`` entry's ``mfcc_frechet`` is the floor: the mean distance from that recording to the
recordings of other performers (performer = file name up to the first ``_``).

``--json`` prints exactly one JSON object on stdout; progress goes to stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from data_schemas.errors import ArcoError, ParameterError  # noqa: E402
from pipelines.reports import baselines, loudness, recordings, timbre, vibrato  # noqa: E402
from pipelines.reports.json_safe import json_safe  # noqa: E402

#: JSON-safe figures, rounded to 3 decimals.
clean = partial(json_safe, digits=3)

SAMPLE_RATE = 44100
VIBRATO = ("vibrato_share", "vibrato_extent_cents", "vibrato_rate_hz",
           "intonation_spread_cents", "level_range_db")
SOURCES = ("real", "rules", "fluidr3", "sawtooth", "frames")
FIGURES = ("mfcc_frechet", "centroid_hz", "h6_10_db", "h11_20_db", "flatness_db", "hnr_db",
           *VIBRATO, "click_ratio", "click_p999")
#: Figures of the engines playing actions, per source and recording (filled while rendering).
EXTRAS: dict[str, dict[str, dict]] = {}


def say(*parts: Any) -> None:
    print(*parts, file=sys.stderr, flush=True)


def shared_recordings() -> list[recordings.Recording]:
    from pipelines.reports.leave_out import shared_recordings_folder

    return recordings.dataset_recordings(shared_recordings_folder())


def given_recordings(triples: list[list[str]]) -> list[recordings.Recording]:
    out = []
    for audio, notes, alignment in triples:
        name = Path(audio).stem
        taken = {r.name for r in out}
        name = name if name not in taken else f"{name}-{len(out)}"
        out.append(recordings.Recording(name, Path(audio), Path(notes), Path(alignment)))
    return out


def make_renderers(args: argparse.Namespace,
                   recs: list[recordings.Recording] | None = None) -> dict[str, Any]:
    """Source name -> function(table, midi_path, n_samples) -> mono audio."""
    from pipelines.perform.config import load_config

    config = load_config(args.rules_config)

    def rules(table, midi, n):
        from pipelines.methods.rules import render
        from pipelines.score import read_score

        res = render(read_score(midi), config, parts=[0], seed=args.seed,
                     sample_rate=SAMPLE_RATE, transpose_octaves=True, progress=False)
        extra = EXTRAS.setdefault("rules", {}).setdefault(table.attrs["recording"], {})
        extra.update(pitch_figures(res.audio, res.parts[0].performance.actions))
        return res.audio

    def method(name, database=None, models=None):
        def play(table, midi, n):
            from pipelines.methods.registry import render_method
            from pipelines.score import read_score

            return render_method(name, read_score(midi), [0], stem=Path(midi).stem,
                                 config=config, database=database, models=models,
                                 seed=args.seed, sample_rate=SAMPLE_RATE,
                                 transpose_octaves=True, diagnostics=False).audio
        return play

    out = {"rules": rules,
           "fluidr3": lambda table, midi, n: baselines.fluidsynth_render(midi, SAMPLE_RATE),
           "sawtooth": lambda table, midi, n: baselines.sawtooth_notes(table, n, SAMPLE_RATE)}
    if args.models:
        out["feedback"] = method("feedback", models=args.models)
    if args.db:
        from pipelines.methods.sampling import open_database

        variant = "sampling" if args.models else "sampling-open"
        out[variant] = method(variant, database=open_database(args.db), models=args.models)
    if "frames" in args.sources:
        out["frames"] = frames_renderer(args, config, recs or [])
    return {k: v for k, v in out.items() if k in args.sources}


def pitch_figures(audio: np.ndarray, actions) -> dict[str, Any]:
    """Pitch error of a render against the pitch its actions ask for (sustained stretches)."""
    from pipelines.reports.joins import pitch_error_cents
    from synth.frames.targets import PitchProfile, derive_targets

    flat = PitchProfile(np.array([0.0, 127.0]), np.zeros(2), np.full(2, 1000.0), (-99.0, 0.0))
    tg = derive_targets(actions, "violin", 512 / SAMPLE_RATE, flat)
    return {f"pitch_{k}": v for k, v in pitch_error_cents(audio, SAMPLE_RATE, tg.times,
                                                          tg.f0).items()}


def dataset_folder(recs: list[recordings.Recording], root: Path) -> Path:
    """A folder laid out like bach-violin with every recording (links), for the build."""
    data = root / "recordings"
    for sub in ("audio", "notes", "alignments"):
        (data / sub).mkdir(parents=True, exist_ok=True)
    for r in recs:
        for src, sub in ((r.audio, "audio"), (r.notes, "notes"), (r.alignment, "alignments")):
            link = data / sub / src.name
            if not link.exists():
                link.symlink_to(src.resolve())
    return data


def frames_renderer(args: argparse.Namespace, config: dict, recs: list[recordings.Recording]):
    """The ``frames`` source: rules' actions on the audio-frame database of every recording,
    the measured one left out (:func:`pipelines.reports.leave_out.without`, as ``arco
    compare --engines``); the database is built once, on first use."""
    import atexit
    import shutil

    root = Path(tempfile.mkdtemp(prefix="arco-frames-"))
    atexit.register(shutil.rmtree, root, ignore_errors=True)
    whole: dict[str, Any] = {}

    def frames(table, midi, n):
        from data_schemas.audio_frames import read_audio_database
        from gesture_db.audio_build import build_audio_database
        from pipelines.methods.rules import render
        from pipelines.reports.leave_out import without
        from pipelines.score import read_score
        from synth.engines import get_engine

        name = table.attrs["recording"]
        if len(recs) < 2:
            raise baselines.PeerMissingError("frames needs at least two recordings")
        t0 = time.perf_counter()
        if "db" not in whole:
            build_audio_database([dataset_folder(recs, root)], root / "db", progress=False)
            whole["db"], whole["build_s"] = read_audio_database(root / "db"), \
                time.perf_counter() - t0
        rec = next(r for r in recs if r.name == name)
        db = without(whole["db"], rec.audio.stem, root / f"db-without-{name}")
        t1 = time.perf_counter()
        actions = render(read_score(midi), config, parts=[0], seed=args.seed, audio=False,
                         sample_rate=SAMPLE_RATE, transpose_octaves=True,
                         progress=False).parts[0].performance.actions
        engine = get_engine("frames", "violin", sample_rate=SAMPLE_RATE, seed=args.seed,
                            audio_db=db)
        engine.render(actions.iloc[:2])  # decode the audio, compile: not part of a render
        t2 = time.perf_counter()
        audio, _ = engine.render(actions, tail=0.5)
        t3 = time.perf_counter()
        again, _ = engine.render(actions, tail=0.5)
        EXTRAS.setdefault("frames", {})[name] = {
            "db_recordings": len(db.audio_paths), "db_build_s": whole["build_s"],
            "setup_s": t2 - t1, "render_s": t3 - t2, "search_s": engine.search_seconds,
            "real_time_factor": (audio.size / SAMPLE_RATE) / (t3 - t2),
            "bit_identical": bool(audio.tobytes() == again.tobytes()),
            **pitch_figures(audio, actions)}
        return audio

    return frames


def failed(reason: str) -> dict[str, Any]:
    return {**dict.fromkeys(FIGURES), "reason": reason}


def read_table(rec: recordings.Recording, seconds: float):
    """The recording's aligned notes that start in the first ``seconds``."""
    if not rec.audio.is_file():
        raise ParameterError(f"{rec.audio}: file not found")
    table = recordings.first_seconds(
        recordings.read_aligned_notes(rec.notes, rec.alignment), seconds)
    if table.empty:
        raise ParameterError(f"{rec.alignment}: no note starts in the first {seconds} s")
    return table


def keep(args: argparse.Namespace, rec: recordings.Recording, source: str, audio: np.ndarray,
         table) -> None:
    """With ``--out``: write the source's loudness-normalised audio as DIR/NAME-SOURCE.wav."""
    if args.out:
        from pipelines.audio_io import write_audio

        write_audio(Path(args.out) / f"{rec.name}-{source}.wav",
                    timbre.normalise_loudness(audio, SAMPLE_RATE, table), SAMPLE_RATE)


def measure_recording(rec: recordings.Recording, args: argparse.Namespace, renderers: dict,
                      workdir: Path) -> tuple[dict[str, Any], np.ndarray]:
    """Render, measure and compare every source for one recording (+ the real MFCC frames)."""
    table = read_table(rec, args.seconds)
    n = int(round(args.seconds * SAMPLE_RATE))
    midi = recordings.write_aligned_midi(table, workdir / f"{rec.name}.mid")
    real_audio = recordings.read_audio(rec.audio, seconds=args.seconds, sample_rate=SAMPLE_RATE)
    keep(args, rec, "real", real_audio, table)
    real = timbre.measure(real_audio, SAMPLE_RATE, table)
    real.figures.update(vibrato.vibrato_figures(real_audio, SAMPLE_RATE, table))
    real.figures.update(clicks(real_audio))
    table.attrs["recording"] = rec.name
    real.figures["level_range_db"] = loudness.level_range_db(real_audio, SAMPLE_RATE, table)
    result: dict[str, Any] = {
        "audio": str(rec.audio), "notes": len(table), "dropped_notes": table.attrs["dropped"],
        "figures": {"real": {"mfcc_frechet": None, **real.figures}},
        "ltas_db": {"real": real.ltas_db}, "ltas_diff_db": {}, "render_seconds": {}}
    for name, render in renderers.items():
        t0 = time.perf_counter()
        try:
            audio = recordings.fit_length(np.asarray(render(table, midi, n), np.float64), n)
        except baselines.PeerMissingError as exc:
            say(f"  {name}: {exc}")
            result["figures"][name] = failed(str(exc))
            continue
        result["render_seconds"][name] = time.perf_counter() - t0
        keep(args, rec, name, audio, table)
        m = timbre.measure(audio, SAMPLE_RATE, table)
        m.figures.update(vibrato.vibrato_figures(audio, SAMPLE_RATE, table))
        m.figures.update(clicks(audio))
        m.figures["level_range_db"] = loudness.level_range_db(audio, SAMPLE_RATE, table)
        result["figures"][name] = {"mfcc_frechet": timbre.frechet_distance(m.mfcc, real.mfcc),
                                   **m.figures}
        result["ltas_db"][name] = m.ltas_db
        result["ltas_diff_db"][name] = {b: m.ltas_db[b] - real.ltas_db[b] for b in m.ltas_db}
        say(f"  {name}: frechet {result['figures'][name]['mfcc_frechet']:.0f}, centroid "
            f"{m.figures['centroid_hz'] or float('nan'):.0f} Hz "
            f"({result['render_seconds'][name]:.1f} s)")
    return result, real.mfcc


def clicks(audio: np.ndarray) -> dict[str, float]:
    """Largest (and 99.9th percentile) sample jump over the local RMS slope."""
    from pipelines.reports.joins import click_ratio

    top, p999 = click_ratio(audio)
    return {"click_ratio": top, "click_p999": p999}


def performer(name: str) -> str:
    return name.split("_")[0]


def floor(per: dict[str, dict], frames: dict[str, np.ndarray]) -> dict[str, Any]:
    """Frechet distances between the real recordings; each recording's mean to other
    performers' recordings becomes its ``real`` ``mfcc_frechet``."""
    names = sorted(frames)
    pairs = []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            pairs.append({"a": a, "b": b, "same_performer": performer(a) == performer(b),
                          "mfcc_frechet": timbre.frechet_distance(frames[a], frames[b])})
    for name in names:
        d = [p["mfcc_frechet"] for p in pairs if name in (p["a"], p["b"])
             and not p["same_performer"]]
        per[name]["figures"]["real"]["mfcc_frechet"] = float(np.mean(d)) if d else None
    across = [p["mfcc_frechet"] for p in pairs if not p["same_performer"]]
    return {"pairs": pairs, "between_performers": float(np.mean(across)) if across else None}


def mean_over(per: dict[str, dict]) -> dict[str, Any]:
    """Each source's figures and LTAS differences averaged over the recordings."""
    sources = list(dict.fromkeys(s for r in per.values() for s in r["figures"]))
    figures, ltas = {}, {}
    for s in sources:
        figures[s] = {}
        for f in FIGURES:
            got = [r["figures"][s] for r in per.values()
                   if s in r["figures"] and r["figures"][s][f] is not None]
            # vibrato figures: pooled over the long notes (recordings weighted by their count)
            w = [g.get("long_notes", 1) if f in VIBRATO else 1 for g in got]
            figures[s][f] = float(np.average([g[f] for g in got], weights=w)) \
                if got and sum(w) > 0 else None
        diffs = [r["ltas_diff_db"][s] for r in per.values() if s in r["ltas_diff_db"]]
        if diffs:
            ltas[s] = {b: float(np.nanmean([d[b] for d in diffs])) for b in diffs[0]}
    return {"figures": figures, "ltas_diff_db": ltas}


def mean_extras(per_rec: dict[str, dict]) -> dict[str, Any]:
    """Each numeric engine figure averaged over the recordings."""
    keys = dict.fromkeys(k for r in per_rec.values() for k in r)
    out = {}
    for k in keys:
        vals = [r[k] for r in per_rec.values() if isinstance(r.get(k), int | float)
                and not isinstance(r.get(k), bool)]
        if vals:
            out[k] = float(np.mean(vals))
    return out


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--recording", nargs=3, action="append", metavar=("AUDIO", "NOTES", "ALIGN"),
                   help="measure against this recording (repeatable; default: the shared "
                        "bach-violin recordings)")
    p.add_argument("--seconds", type=float, default=30.0, help="first N seconds (default 30)")
    p.add_argument("--out", metavar="DIR", help="keep the (loudness-normalised) WAVs and MIDI")
    p.add_argument("--sources", default=",".join(SOURCES),
                   help=f"comma-separated subset of {','.join(SOURCES)} (real is always "
                        "measured)")
    p.add_argument("--models", metavar="DIR", help="also render with the feedback method")
    p.add_argument("--db", metavar="DB", help="also render with the sampling method")
    p.add_argument("--seed", type=int, default=0, help="seed of Arco's renders (default 0)")
    p.add_argument("--rules-config", metavar="TOML",
                   help="rules configuration merged over the defaults (e.g. vibrato off)")
    args = p.parse_args(argv)
    if args.seconds <= 0:
        raise ParameterError(f"--seconds {args.seconds} must be > 0")
    args.sources = [s.strip() for s in args.sources.split(",") if s.strip()]
    bad = [s for s in args.sources if s not in SOURCES]
    if bad:
        raise ParameterError(f"--sources: unknown {', '.join(bad)} (choose from "
                             f"{', '.join(SOURCES)})")
    args.sources += [m for m, on in (("feedback", args.models), ("sampling", args.db),
                                     ("sampling-open", args.db and not args.models)) if on]
    if args.models and not Path(args.models).is_dir():
        raise ParameterError(f"--models {args.models}: no such directory")
    return args


def run(args: argparse.Namespace) -> dict[str, Any]:
    started = time.perf_counter()
    recs = given_recordings(args.recording) if args.recording else shared_recordings()
    for rec in recs:  # every input checked before any render
        read_table(rec, args.seconds)
    renderers = make_renderers(args, recs)
    per: dict[str, dict] = {}
    frames: dict[str, np.ndarray] = {}
    with tempfile.TemporaryDirectory() as tmp:
        workdir = Path(args.out) if args.out else Path(tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        for rec in recs:
            say(f"{rec.name}:")
            per[rec.name], frames[rec.name] = measure_recording(rec, args, renderers, workdir)
    floors = floor(per, frames)
    return clean({
        "settings": {"seconds": args.seconds, "sample_rate": SAMPLE_RATE,
                     "fmax_hz": timbre.FMAX, "n_fft": timbre.N_FFT, "hop": timbre.HOP,
                     "loudness": f"RMS over sounding samples = {timbre.TARGET_RMS}",
                     "mfcc": f"c1-c{timbre.N_MFCC} of {timbre.N_MELS} mel bands",
                     "seed": args.seed},
        "sources": ["real", *renderers],
        "recordings": per,
        "mean": mean_over(per),
        "floor": floors,
        "engines": {src: {"recordings": per_rec, "mean": mean_extras(per_rec)}
                    for src, per_rec in EXTRAS.items()},
        "elapsed_s": time.perf_counter() - started,
    })


def main(argv: list[str] | None = None) -> int:
    try:
        args = parse_args(argv)
        report = run(args)
    except ArcoError as exc:
        print(f"timbre: error: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        print_table(report)
    return 0


def print_table(report: dict[str, Any]) -> None:
    """The mean figures, one line per source."""
    figures = report["mean"]["figures"]
    print(f"{'source':<14}" + "".join(f"{f:>14}" for f in FIGURES))
    for source, row in figures.items():
        print(f"{source:<14}" + "".join(
            f"{'-' if row[f] is None else format(row[f], '.1f'):>14}" for f in FIGURES))
    print(f"elapsed {report['elapsed_s']:.0f} s")


if __name__ == "__main__":
    raise SystemExit(main())
