"""Does the yardstick agree with itself? Slip record vs audio only, renders and recordings.

    python bench/yardstick.py --json [--quick]

Renders quartet excerpts with the ``rules`` method (violin, viola and cello parts of the
bundled Mozart K. 421 and of OpenScore quartets; contact diagnostics with the slip record)
and evaluates each render twice, from the slip record and from the audio alone. Reports,
per excerpt, over the Mozart parts the audio path's thresholds were chosen on (``tuning``),
over the other pieces (``held_out``) and over all, the two Helmholtz shares and attack
medians/p90, and per note the mean absolute, median signed and largest difference of the
two paths (attacks over the notes both time; notes starting as double stops have none).
Then evaluates the real recordings of ``shared/data/bach-violin`` from the audio alone,
notes from their alignments.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
QUARTETS = ROOT.parent / "shared" / "data" / "openscore-quartets"
BACH = ROOT.parent / "shared" / "data" / "bach-violin"
#: (name, score, part index, first and last measure). The Mozart K. 421 parts chose the
#: audio path's thresholds (:data:`TUNED_ON`); the others are held out.
EXCERPTS = [
    ("mozart-k421 violin I m1-4", ROOT / "pipelines/data/mozart-k421.mxl", 0, 1, 4),
    ("mozart-k421 violin II m1-6", ROOT / "pipelines/data/mozart-k421.mxl", 1, 1, 6),
    ("mozart-k421 viola m1-6", ROOT / "pipelines/data/mozart-k421.mxl", 2, 1, 6),
    ("mozart-k421 cello m1-6", ROOT / "pipelines/data/mozart-k421.mxl", 3, 1, 6),
    ("haydn op74/1 violin I m1-6",
     QUARTETS / "Haydn-Joseph-String-Quartet-in-C-major-Hob.III72-Op.74-No.1-sq10372717.mxl",
     0, 1, 6),
    ("beethoven op18/1 viola m1-8",
     QUARTETS / "Beethoven-Ludwig-van-String-Quartet-No.1-Op.18-No.1-sq8071278.mxl", 2, 1, 8),
    ("dvorak op51 cello m1-6",
     QUARTETS / "Dvorak-Antonin-String-Quartet-No.10-Op.51-sq9137469.mxl", 3, 1, 6),
    ("haydn op76/2 violin II m1-8",
     QUARTETS / "Haydn-Joseph-String-Quartet-in-D-minor-Hob.III76-Op.76-No.2-sq12772795.mxl",
     1, 1, 8),
    ("mozart k387 cello m1-8",
     QUARTETS / "Mozart-Wolfgang-Amadeus-String-Quartet-No.14-in-G-major-K.387-Op.-10-No.-1"
     "-sq7103818.mxl", 3, 1, 8),
]

#: Excerpts whose notes the audio path's thresholds were chosen on.
TUNED_ON = "mozart-k421"


def _differences(a: list, b: list, key: str, scale: float = 1.0) -> dict:
    x = np.array([n[key] for n in a], np.float64) * scale
    y = np.array([n[key] for n in b], np.float64) * scale
    both = np.isfinite(x) & np.isfinite(y)
    signed = (y - x)[both]
    d = np.abs(signed)
    return {"notes": int(both.sum()),
            "median_audio_minus_slips": float(np.median(signed)) if d.size else None,
            "mean_abs": float(d.mean()) if d.size else None,
            "median_abs": float(np.median(d)) if d.size else None,
            "max": float(d.max()) if d.size else None,
            "share_within": float(np.mean(d <= (0.05 if key == "helmholtz_share" else 10.0)))
            if d.size else None}


def _compare(slip_notes: list, audio_notes: list) -> dict:
    from pipelines.listening.evaluate import piece_figures

    pa, pb = piece_figures(slip_notes), piece_figures(audio_notes)
    return {"notes": pa["notes"], "sustained_hops": pa["sustained_hops"],
            **{f"{k}_{src}": p[k] for src, p in (("slips", pa), ("audio", pb))
               for k in ("helmholtz_share", "attack_ms_median", "attack_ms_p90")},
            "note_helmholtz_share": _differences(slip_notes, audio_notes, "helmholtz_share"),
            "note_attack_ms": _differences(slip_notes, audio_notes, "attack_ms")}


def renders(quick: bool) -> dict:
    """Render each excerpt once and compare the two paths (per excerpt, tuning, held out)."""
    from pipelines.listening.evaluate import evaluate
    from pipelines.methods.render import render_score

    out, groups = {}, {"tuning": ([], []), "held_out": ([], []), "all": ([], [])}
    for name, score, part, m0, m1 in EXCERPTS[:2] if quick else EXCERPTS:
        t = time.perf_counter()
        p = render_score(score, method="rules", parts=part, start_measure=m0, end_measure=m1,
                         diagnostics=True, seed=0).parts[0]
        a = evaluate(p.audio, p.actions, diagnostics=p.diagnostics, instrument=p.instrument)
        b = evaluate(p.audio, p.actions, instrument=p.instrument)
        for g in ("tuning" if name.startswith(TUNED_ON) else "held_out", "all"):
            groups[g][0].extend(a["notes"])
            groups[g][1].extend(b["notes"])
        out[name] = {"instrument": p.instrument, **_compare(a["notes"], b["notes"]),
                     "seconds": round(time.perf_counter() - t, 1)}
    for g, (slip_notes, audio_notes) in groups.items():
        if slip_notes:
            out[g] = _compare(slip_notes, audio_notes)
    return out


def recordings() -> dict:
    """Audio-only figures of the real recordings, notes from their alignments."""
    from pipelines.listening.evaluate import evaluate
    from pipelines.reports.recordings import dataset_recordings, read_aligned_notes, read_audio

    out = {}
    for rec in dataset_recordings(BACH):
        notes = read_aligned_notes(rec.notes, rec.alignment)
        r = evaluate(read_audio(rec.audio), timed_notes=notes)
        att = np.array([n["attack_ms"] for n in r["notes"]], np.float64)
        att = att[np.isfinite(att)]
        out[rec.name] = {k: r["piece"][k] for k in ("notes", "sustained_hops",
                                                    "helmholtz_share", "attack_ms_median",
                                                    "attack_ms_p90", "reached_helmholtz_share",
                                                    "pitch_error_cents_median")}
        out[rec.name].update(timed_attacks=int(att.size),
                             attack_ms_p10=float(np.percentile(att, 10)) if att.size else None)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--quick", action="store_true", help="two excerpts, no recordings")
    args = ap.parse_args()
    result = {"renders": renders(args.quick)}
    if not args.quick:
        result["recordings"] = recordings()
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for group, rows in result.items():
            for name, row in rows.items():
                print(group, name, {k: v for k, v in row.items() if not isinstance(v, dict)})


if __name__ == "__main__":
    main()
