"""arco simulate-recordings, build-db and db info, through the real ``arco`` entry point."""

import json

from pipelines.cli.main import main


def test_cli_round_trip(tmp_path, capsys):
    rec, out = tmp_path / "rec", tmp_path / "db"
    assert main(["simulate-recordings", "--notes", "60", "--performers", "2", "--seed", "1",
                 "--notes-per-take", "30", "-o", str(rec)]) == 0
    assert main(["build-db", str(rec), "-o", str(out), "--workers", "1"]) == 0
    capsys.readouterr()
    assert main(["db", "info", str(out), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["n_notes"] == 60
    assert info["median_boundary_error_ms"] <= 10 and info["notes_found_share"] >= 0.98
    assert len(info["plots"]) == info["n_groups"]
    assert main(["db", "info", str(tmp_path), "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("arco db: error:") and "\n" not in err
