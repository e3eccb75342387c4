"""Start-up time of the ``arco`` command line: ``arco --help`` and each sub-command's --help.

Each command runs in a fresh Python process (``python -m pipelines.cli.main ... --help``, so
the tree on ``PYTHONPATH`` is measured, not an installed copy); the figure is the median
wall-clock time of ``--repeats`` runs. The target is under 0.5 s each.

    python bench/cli_speed.py --json
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_S = 0.5


def command_paths() -> list[list[str]]:
    """Every sub-command of ``arco``, nested ones (``db info``) included."""
    sys.path.insert(0, str(ROOT))
    from pipelines.cli.main import build_parser

    def walk(parser, prefix):
        out = []
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    out.append([*prefix, name])
                    out.extend(walk(sub, [*prefix, name]))
        return out

    return walk(build_parser(), [])


def time_help(argv: list[str], repeats: int) -> float:
    """Median seconds of ``arco ARGV --help`` in fresh processes."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "pipelines.cli.main", *argv, "--help"],
                       check=True, capture_output=True, env=env, cwd=ROOT)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> int:
    """Time every command's help; print a table or one JSON object."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--repeats", type=int, default=5, help="runs per command (median)")
    args = parser.parse_args()
    commands = [[], *command_paths()]
    seconds = {" ".join(["arco", *c, "--help"]): round(time_help(c, args.repeats), 4)
               for c in commands}
    worst = max(seconds.values())
    result = {"benchmark": "cli_speed", "repeats": args.repeats, "target_s": TARGET_S,
              "max_s": worst, "all_under_target": worst < TARGET_S, "median_s": seconds}
    if args.json:
        print(json.dumps(result))
    else:
        for name, s in seconds.items():
            print(f"{s:7.3f} s  {name}")
        print(f"slowest {worst:.3f} s (target < {TARGET_S} s)")
    return 0 if worst < TARGET_S else 1


if __name__ == "__main__":
    sys.exit(main())
