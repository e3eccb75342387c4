"""Peak memory (RSS) of rendering and mixing against the length of the music.

Each measurement runs in a fresh Python process and reports its ``ru_maxrss``:

* ``mix``: the streaming ensemble mix alone (:func:`pipelines.ensemble.mixdown.mixdown`: four
  parts panned, the hall, the loudness pass, master and stems written) on four mono WAVs of
  the given length (noise-like tones, written block by block first);
* ``render``: ``render_score`` of a synthetic quartet (four parts of one-second notes, the
  rules on the modal engine) spooling each part to disk, plus the ensemble mix, as
  ``arco render --all-parts`` does; ``render-held`` the same with every part's audio kept
  in memory until the mix (how it was before, and what a method that cannot spool costs);
  ``solo``: one part (violin I) rendered and written as a mono WAV, as ``arco render -o``.

The target (issue 16): a 10-minute render within 1.5x of a 10-second one, an 11.5-minute
quartet movement with ``--all-parts`` under 600 MB.

    python bench/memory.py --json
    python bench/memory.py --mix-seconds 10,690 --render-seconds 10,690 --solo-seconds 10,600 --held
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_RATIO = 1.5
TARGET_QUARTET_MB = 600.0


def _quartet_notes(seconds: float):
    import pandas as pd

    from pipelines.methods.feedback import scale_notes

    template = scale_notes(tonic=62, octaves=1).iloc[0].to_dict()
    pitches = {0: (67, 71, 74, 76), 1: (62, 66, 69, 71), 2: (55, 59, 62, 64),
               3: (43, 47, 50, 52)}
    names = {0: "violin", 1: "violin", 2: "viola", 3: "cello"}
    rows = []
    for part in range(4):
        for i in range(int(seconds)):
            rows.append({**template, "part_index": part, "part_name": f"p{part}",
                         "part_id": f"P{part}", "instrument": names[part],
                         "measure": 1 + i // 4, "onset": float(i), "duration": 1.0,
                         "onset_beats": float(i), "duration_beats": 1.0,
                         "midi_pitch": pitches[part][i % 4]})
    return pd.DataFrame(rows)


def _child(kind: str, seconds: float, folder: Path) -> dict:
    import numpy as np

    from pipelines.ensemble.config import load_ensemble
    from pipelines.ensemble.wav_stream import audio_writer

    start = time.perf_counter()
    rate = 44100
    if kind == "mix":
        from pipelines.ensemble.mixdown import mixdown

        sources = []
        rng = np.random.default_rng(0)
        for k in range(4):
            sources.append(folder / f"src{k}.wav")
            with audio_writer(sources[-1], rate, 1) as out:
                for at in range(0, int(seconds * rate), 65536):
                    n = min(65536, int(seconds * rate) - at)
                    out.write(0.05 * rng.standard_normal(n).astype(np.float32))
        base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        report = mixdown(sources, folder / "mix.wav", pans=[-0.7, -0.25, 0.25, 0.7],
                         ensemble=load_ensemble(),
                         stems=[folder / f"stem{k}.wav" for k in range(4)])
    elif kind == "solo":
        from pipelines.audio_io import write_audio
        from pipelines.methods.render import render_score

        base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        output = render_score(_quartet_notes(seconds), method="rules", parts=0, seed=0)
        write_audio(folder / "solo.wav", output.audio, rate)
        report = argparse.Namespace(seconds=output.audio.size / rate, loudness=float("nan"),
                                    peak_db=float("nan"))
    else:
        from pipelines.ensemble.ensemble_output import write_ensemble
        from pipelines.ensemble.spool import AudioSpool
        from pipelines.methods.render import render_score

        base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        spool = AudioSpool(folder, rate) if kind == "render" else None  # as arco render does
        output = render_score(_quartet_notes(seconds), method="rules", parts="all", seed=0,
                              spool=spool)
        report = write_ensemble(output, folder / "mix.wav", sample_rate=rate,
                                ensemble=load_ensemble(), spool=spool)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return {"kind": kind, "music_s": seconds, "audio_s": round(report.seconds, 2),
            "peak_rss_mb": round(peak, 1), "rss_before_work_mb": round(base, 1),
            "wall_s": round(time.perf_counter() - start, 1),
            "loudness_lufs": round(report.loudness, 2), "peak_dbfs": round(report.peak_db, 2)}


def measure(kind: str, seconds: float) -> dict:
    """Run one measurement in a fresh process and return its figures."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    run = subprocess.run([sys.executable, __file__, "--child", kind, str(seconds)],
                         check=True, capture_output=True, text=True, env=env, cwd=ROOT)
    return json.loads(run.stdout.strip().splitlines()[-1])


def main() -> int:
    """Measure; print a table or one JSON object."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--mix-seconds", default="10,600,690",
                        help="lengths of the mix-only runs, s")
    parser.add_argument("--render-seconds", default="10,40",
                        help="lengths of the full quartet renders, s")
    parser.add_argument("--solo-seconds", default="10,600",
                        help="lengths of the single-part renders, s")
    parser.add_argument("--held", action="store_true",
                        help="also measure renders that hold every part (render-held)")
    parser.add_argument("--child", nargs=2, metavar=("KIND", "SECONDS"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        with tempfile.TemporaryDirectory() as folder:
            print(json.dumps(_child(args.child[0], float(args.child[1]), Path(folder))))
        return 0
    runs = [measure("mix", float(s)) for s in args.mix_seconds.split(",") if s]
    runs += [measure(kind, float(s)) for kind in ("render", "render-held")[:1 + args.held]
             for s in args.render_seconds.split(",") if s]
    runs += [measure("solo", float(s)) for s in args.solo_seconds.split(",") if s]
    mix = [r for r in runs if r["kind"] == "mix"]
    result = {"runs": runs, "target_ratio": TARGET_RATIO, "target_quartet_mb": TARGET_QUARTET_MB}
    if len(mix) > 1:
        result["mix_ratio_longest_to_shortest"] = round(
            mix[-1]["peak_rss_mb"] / mix[0]["peak_rss_mb"], 3)
    for kind in ("render", "render-held", "solo"):
        render = [r for r in runs if r["kind"] == kind]
        if len(render) > 1:
            slope = (render[-1]["peak_rss_mb"] - render[0]["peak_rss_mb"]) / (
                render[-1]["music_s"] - render[0]["music_s"])
            result[f"{kind}_mb_per_music_s"] = round(slope, 3)
            result[f"{kind}_690s_quartet_mb_extrapolated"] = round(
                render[0]["peak_rss_mb"] + slope * (690 - render[0]["music_s"]), 1)
            result[f"{kind}_ratio_longest_to_shortest"] = round(
                render[-1]["peak_rss_mb"] / render[0]["peak_rss_mb"], 3)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for r in runs:
            print(f"{r['kind']:7s} {r['music_s']:7.0f} s music: peak {r['peak_rss_mb']:7.1f} MB "
                  f"({r['wall_s']} s)")
        print({k: v for k, v in result.items() if k != "runs"})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
