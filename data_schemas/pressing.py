"""The pressing limits: from which bow force the instrument model's strings sound flat.

One row per instrument, string, bow velocity and beta, measured by
``bench/calibrate_pressing.py`` (steady open-string strokes at forces from 0.6 to 1.9 times
the middle of the string's Helmholtz window, YIN pitch of the settled part); gesture
sampling reads it to keep sampled forces below the force that flattens the pitch
(``pipelines/methods/pressing.py``).
"""

from __future__ import annotations

import pyarrow as pa

from data_schemas.spec import Column, TableSpec

PRESSING_LIMITS = TableSpec(
    name="pressing_limits",
    version="1.0",
    description="Bow force, as a multiple of the middle of the string's Helmholtz window, "
                "above which the instrument model's open string in Helmholtz motion sounds "
                "flatter than at light force by more than the table's drop; one row per "
                "instrument, string, bow velocity and beta.",
    columns=(
        Column("instrument", pa.string(), "", "violin, viola or cello."),
        Column("string", pa.int8(), "1", "String index, 0 = lowest.", minimum=0, maximum=3),
        Column("bow_velocity", pa.float64(), "m/s", "Bow speed of the strokes.",
               minimum=0.01, maximum=2.0),
        Column("beta", pa.float64(), "1",
               "Bow-bridge distance / effective string length.", minimum=0.01, maximum=0.5),
        Column("measured_multiple", pa.float64(), "1",
               "The largest force tried (times pipelines.methods.playable.window_middle) "
               "below every flat one; the largest tried when none went flat.",
               minimum=0.0, maximum=10.0),
        Column("multiple", pa.float64(), "1",
               "The limit used: measured_multiple made non-decreasing in beta per string "
               "and bow velocity (nearer the bridge flattens sooner).",
               minimum=0.0, maximum=10.0),
        Column("drop_cents", pa.float64(), "cent",
               "How much flatter than the light strokes counts as flat.", minimum=0.0,
               maximum=100.0),
        Column("key", pa.string(), "",
               "Hash of the string physics and instrument facts it was measured with (stale "
               "when they change)."),
    ),
)
