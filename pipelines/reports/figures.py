"""The figures a comparison reports, and which way each is better."""

from __future__ import annotations

#: Figures compared between methods and whether larger is better (None: closer to 0).
FIGURES = {
    "reached_helmholtz_share": True,
    "helmholtz_share": True,
    "sustained_class3_share": True,
    "attack_ms_median": False,
    "attack_ms_p90": False,
    "pitch_error_cents_median": None,
    "level_error_db_median": None,
    "render_seconds": False,
}
