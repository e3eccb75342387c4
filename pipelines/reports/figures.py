"""The figures a comparison reports, and which way each is better."""

from __future__ import annotations

#: Scored figures and whether larger is better (None: closer to 0 is better).
FIGURES = {
    "helmholtz_share": True,
    "attack_ms_p90": False,
    "sustained_class3_share": True,
    "sustained_class5_share": False,
    "reached_helmholtz_share": True,
    "attack_ms_median": False,
    "pitch_error_cents_median": None,
    "level_error_db_median": None,
}

#: Figures reported beside the scored ones but never scored or highlighted.
REPORTED = ("render_seconds", "real_time_factor")

#: How the report names each figure (the verdict sentence and the tables).
LABELS = {
    "helmholtz_share": "Helmholtz share",
    "attack_ms_p90": "attack p90",
    "sustained_class3_share": "class-3 share",
    "sustained_class5_share": "class-5 share",
    "reached_helmholtz_share": "notes reaching Helmholtz motion",
    "attack_ms_median": "attack median",
    "pitch_error_cents_median": "pitch error",
    "level_error_db_median": "level error",
    "render_seconds": "render time (s, not scored)",
    "real_time_factor": "real-time factor (not scored)",
}
