"""arco simulate-recordings, build-db and db info."""

import argparse
import json

from pipelines.cli.commands import build_db, db, simulate_recordings


def _main(argv):
    from data_schemas.errors import ArcoError

    parser = argparse.ArgumentParser(prog="arco")
    sub = parser.add_subparsers(dest="command", required=True)
    for mod in (simulate_recordings, build_db, db):
        mod.register(sub)
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except ArcoError:
        return 2


def test_cli_round_trip(tmp_path, capsys):
    rec, out = tmp_path / "rec", tmp_path / "db"
    assert _main(["simulate-recordings", "--notes", "60", "--performers", "2", "--seed", "1",
                  "--notes-per-take", "30", "-o", str(rec)]) == 0
    assert _main(["build-db", str(rec), "-o", str(out), "--workers", "1"]) == 0
    capsys.readouterr()
    assert _main(["db", "info", str(out), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["n_notes"] == 60
    assert info["median_boundary_error_ms"] <= 10 and info["notes_found_share"] >= 0.98
    assert len(info["plots"]) == info["n_groups"]
    assert _main(["db", "info", str(tmp_path), "--json"]) == 2
