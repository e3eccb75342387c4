"""Real-time factors of the modal bowed string against its peers.

Usage: ``python bench/synth_speed.py --json`` (``make bench`` installs Debian's libstk-dev
for the STK peer first). Prints one JSON object; each entry gives the real-time factor
(audio seconds per CPU second, median of 5, single thread), the number of modes per string
and the internal sample rate. Artifastring (``shared/peers/artifastring/run.sh``, built with
g++ and Debian's libfftw3-dev, which ``make bench`` installs) is timed in the same run, and
the ratios of Arco's figures to its figures are reported.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from synth import Instrument, render_actions  # noqa: E402

SECONDS = 30.0
REPEATS = 5
HERE = Path(__file__).resolve().parent


def steady_actions(strings: list[int], seconds: float) -> pd.DataFrame:
    """Bow ``strings`` steadily (beta 0.12, 1.0 N, 0.4 m/s) for ``seconds``."""
    rows = [(t, s, 0.0, 1.0, 0.4, 0.12, 0.5, False) for s in strings for t in (0.0, seconds)]
    rows.sort()
    return pd.DataFrame(rows, columns=["time", "string", "finger_ratio", "bow_force",
                                       "bow_velocity", "beta", "bow_position", "pluck"])


def time_render(strings: list[int], **settings) -> dict:
    """Median real-time factor of rendering the steady stroke with ``settings``."""
    actions = steady_actions(strings, SECONDS)
    render_actions(steady_actions(strings, 0.05), instrument=Instrument(**settings), tail=0.0)
    times = []
    for _ in range(REPEATS):
        inst = Instrument(**settings)
        start = time.process_time()
        audio = render_actions(actions, instrument=inst, tail=0.0)
        times.append(time.process_time() - start)
        assert np.all(np.isfinite(audio))
    return {"real_time_factor": round(SECONDS / float(np.median(times)), 1),
            "modes": {inst.constants.strings[s].name: inst.voices[s].basis.n_modes
                      for s in strings},
            "internal_rate_hz": inst.internal_rate}


def time_stk() -> dict:
    """Compile the tiny STK driver and time Bowed for 30 s (None with a reason if we cannot)."""
    compiler = shutil.which("g++")
    header = Path("/usr/include/stk/Bowed.h")
    if compiler is None or not header.exists():
        return {"real_time_factor": None,
                "reason": "needs g++ and Debian's libstk-dev (make bench installs them)"}
    with tempfile.TemporaryDirectory() as tmp:
        exe = Path(tmp) / "stk_bowed"
        build = subprocess.run([compiler, "-O3", "-o", str(exe), str(HERE / "stk_bowed.cpp"),
                                "-lstk"], capture_output=True, text=True)
        if build.returncode != 0:
            return {"real_time_factor": None, "reason": f"build failed: {build.stderr[-300:]}"}
        times = []
        for _ in range(REPEATS):
            out = subprocess.run([str(exe), str(SECONDS)], capture_output=True, text=True,
                                 check=True)
            times.append(float(out.stdout.split()[0]))
    return {"real_time_factor": round(SECONDS / float(np.median(times)), 1), "modes": None,
            "internal_rate_hz": 44100, "note": "digital waveguide, one voice, no body"}


def artifastring_dir() -> Path | None:
    """The Artifastring peer beside the repository (``$ARCO_SHARED/peers`` or ``../shared``)."""
    for base in (os.environ.get("ARCO_SHARED"), HERE.parents[1] / "shared", "/work/shared"):
        if base and (Path(base) / "peers" / "artifastring" / "run.sh").exists():
            return Path(base) / "peers" / "artifastring"
    return None


def time_artifastring() -> dict:
    """Artifastring's own harness, same run (cases a: D string full chain, b: four strings)."""
    peer = artifastring_dir()
    if peer is None:
        return {"reason": "shared/peers/artifastring not found (set ARCO_SHARED)"}
    run = subprocess.run(["bash", str(peer / "run.sh"), "--seconds", str(int(SECONDS)),
                          "--runs", str(REPEATS), "--cases", "a,b", "--wav", ""],
                         capture_output=True, text=True)
    if run.returncode != 0:
        return {"reason": f"run.sh failed: {run.stderr.strip()[-300:]}"}
    return json.loads(run.stdout)


def _rtf(entry: object) -> float | None:
    """The CPU real-time factor of one of the peer's cases (``rtf_cpu_median``)."""
    if isinstance(entry, dict):
        for key in ("rtf_cpu_median", "real_time_factor", "rtf"):
            if isinstance(entry.get(key), int | float):
                return float(entry[key])
    return float(entry) if isinstance(entry, int | float) else None


def ratios(result: dict, peer: dict) -> dict:
    """Arco's real-time factors over Artifastring's (same run)."""
    cases = peer.get("cases", peer)
    a = _rtf(cases.get("a_d_string_full")) if isinstance(cases, dict) else None
    b = _rtf(cases.get("b_four_strings_full")) if isinstance(cases, dict) else None
    out = {}
    if a:
        out["d_string_equivalent_over_artifastring"] = round(
            result["d_string_equivalent"]["real_time_factor"] / a, 2)
    if b:
        out["all_strings_over_artifastring"] = round(
            result["all_strings"]["real_time_factor"] / b, 2)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()
    result = {
        "seconds_of_audio": SECONDS,
        "d_string_default": time_render([1]),
        "d_string_equivalent": time_render([1], oversample=2, max_modes=76,
                                           max_mode_frequency=None),
        "all_strings": time_render([0, 1, 2, 3]),
        "stk_bowed": time_stk(),
    }
    result["artifastring"] = time_artifastring()
    result["ratios"] = ratios(result, result["artifastring"])
    print(json.dumps(result, indent=None if args.json else 2))


if __name__ == "__main__":
    main()
