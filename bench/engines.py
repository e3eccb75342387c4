"""Speed of the recorded-audio engines: database build, search and render of a long score.

- ``build``: ``gesture_db.audio_build.build_audio_database`` of the shared Bach recordings
  (``$ARCO_SHARED_DATA/bach-violin``, else ``/work/shared/data/bach-violin``) into a fresh
  temporary folder, wall-clock seconds (``--workers``, default one per CPU);
- ``frames``: a seeded score of ``--notes`` notes (default 1,000; pitches G3..E6, 0.15-0.6 s
  each, rests between some) played by the rules; the ``frames`` engine's search (targets,
  candidates, Viterbi) and whole render timed on the database just built (after a warm-up
  render that decodes the audio and compiles the kernel), the real-time factor, and
  whether a second render is bit-identical;
- ``cws``: the same score through the ``cws`` engine on the same database: training (EM
  and the samples, once per database), its search (notes of every voice, eq. 4's cluster,
  the sample and the experts' pitch and volume of every note: ``CwsEngine.search``) and
  whole render timed after a warm-up render, the real-time factor and bit-identity.

Search and render are timed wall-clock and in this process's CPU seconds (``*_cpu_s``);
the 1-minute load average is reported beside them.

``--json`` prints exactly one JSON object on stdout; progress goes to stderr.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

SAMPLE_RATE = 44100


def say(*parts) -> None:
    print(*parts, file=sys.stderr, flush=True)


def dataset() -> Path:
    from data_schemas.errors import ArcoError
    from pipelines.shared_data import shared_data_dir

    try:
        return shared_data_dir("bach-violin") / "bach-violin"
    except ArcoError as exc:
        raise SystemExit(f"bench/engines.py: {exc}") from None


def long_score(n_notes: int, seed: int) -> pd.DataFrame:
    """Aligned notes (start_s, end_s, midi_pitch, velocity) of a seeded melody."""
    rng = np.random.default_rng(seed)
    dur = rng.uniform(0.15, 0.6, n_notes)
    rest = np.where(rng.random(n_notes) < 0.15, rng.uniform(0.05, 0.3, n_notes), 0.0)
    start = np.concatenate([[0.5], 0.5 + np.cumsum(dur + rest)[:-1]])
    pitch = np.clip(67 + np.cumsum(rng.integers(-4, 5, n_notes)), 55, 88)
    return pd.DataFrame({"start_s": start, "end_s": start + dur, "midi_pitch": pitch,
                         "velocity": rng.integers(50, 100, n_notes)})


def cpu_seconds() -> float:
    """CPU seconds of this process and its finished children (load-independent timing)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def run(args: argparse.Namespace) -> dict:
    from gesture_db.audio_build import build_audio_database
    from pipelines.methods.rules import render
    from pipelines.perform.config import load_config
    from pipelines.reports.recordings import write_aligned_midi
    from pipelines.score import read_score
    from synth.engines import get_engine

    out: dict = {"settings": {"notes": args.notes, "seed": args.seed, "workers": args.workers}}
    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "db"
        say("building the audio-frame database ...")
        t0, c0 = time.perf_counter(), cpu_seconds()
        m = build_audio_database([dataset()], db, workers=args.workers, progress=False)
        out["build"] = {"seconds": time.perf_counter() - t0, "cpu_seconds": cpu_seconds() - c0,
                        "load_average_1min": os.getloadavg()[0],
                        "recordings": len(m["recordings"]),
                        "frames": m["n_frames"], "notes": m["n_notes"],
                        "audio_seconds": m["n_frames"] * m["hop_s"]}
        midi = write_aligned_midi(long_score(args.notes, args.seed), Path(tmp) / "long.mid")
        say(f"rules: {args.notes} notes ...")
        actions = render(read_score(midi), load_config(None), parts=[0], seed=args.seed,
                         audio=False, transpose_octaves=True,
                         progress=False).parts[0].performance.actions
        t0 = time.perf_counter()
        engine = get_engine("frames", "violin", sample_rate=SAMPLE_RATE, audio_db=db)
        t_index = time.perf_counter() - t0
        engine.render(actions.iloc[:2])  # decode audio, compile the kernel
        t_setup = time.perf_counter() - t0
        say("frames: search and render ...")
        t0, c0 = time.perf_counter(), time.process_time()
        engine.search(actions)
        t_search, c_search = time.perf_counter() - t0, time.process_time() - c0
        t0, c0 = time.perf_counter(), time.process_time()
        audio, _ = engine.render(actions)
        t_render, c_render = time.perf_counter() - t0, time.process_time() - c0
        again, _ = engine.render(actions)
        out["frames"] = {"index_build_s": t_index, "setup_s": t_setup, "search_s": t_search,
                         "search_cpu_s": c_search, "render_s": t_render,
                         "render_cpu_s": c_render, "audio_s": audio.size / SAMPLE_RATE,
                         "real_time_factor": audio.size / SAMPLE_RATE / t_render,
                         "real_time_factor_cpu": audio.size / SAMPLE_RATE / c_render,
                         "load_average_1min": os.getloadavg()[0],
                         "action_rows": len(actions),
                         "bit_identical": bool(audio.tobytes() == again.tobytes())}
        out["cws"] = _cws(db, actions)
    return out


def _timed(fn) -> tuple[object, float, float]:
    t0, c0 = time.perf_counter(), time.process_time()
    got = fn()
    return got, time.perf_counter() - t0, time.process_time() - c0


def _cws(db: Path, actions: pd.DataFrame) -> dict:
    """Training, search and render of the ``cws`` engine (see the module docstring)."""
    from synth.engines import get_engine

    say("cws: training ...")
    engine = get_engine("cws", "violin", sample_rate=SAMPLE_RATE, audio_db=db)
    _, t_train, c_train = _timed(lambda: engine.model)
    engine.render(actions.iloc[:400])  # decode the samples' kernels, compile
    say("cws: search and render ...")
    _, t_search, c_search = _timed(lambda: engine.search(actions))
    (audio, _), t_render, c_render = _timed(lambda: engine.render(actions))
    again, _ = engine.render(actions)
    return {"train_s": t_train, "train_cpu_s": c_train, "search_s": t_search,
            "search_cpu_s": c_search, "render_s": t_render, "render_cpu_s": c_render,
            "audio_s": audio.size / SAMPLE_RATE,
            "real_time_factor": audio.size / SAMPLE_RATE / t_render,
            "real_time_factor_cpu": audio.size / SAMPLE_RATE / c_render,
            "load_average_1min": os.getloadavg()[0],
            "bit_identical": bool(audio.tobytes() == again.tobytes())}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--notes", type=int, default=1000, help="notes of the long score")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--workers", type=int, default=None, help="build workers (default: CPUs)")
    args = p.parse_args(argv)
    report = run(args)
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        for section, figures in report.items():
            print(section, ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                                     for k, v in figures.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
