"""The loudness calibration table: how loud the instrument model plays a steady note.

Rows per instrument, string, finger position and dynamic level (one for each bow direction;
at mf also positions 10 cents flat and sharp of each stopped one), measured by
``bench/calibrate_loudness.py`` (steady notes at the rules' bow lanes, BS.1770 loudness);
the rules read it to even out loudness like a player (``pipelines/perform/loudness.py``).
"""

from __future__ import annotations

import pyarrow as pa

from data_schemas.spec import Column, TableSpec

LOUDNESS_CALIBRATION = TableSpec(
    name="loudness_calibration",
    version="1.0",
    description="Loudness of steady notes played by the instrument model at the rules' bow "
                "lanes, rows per instrument, string, finger position (and at mf 10 cents "
                "off it) and dynamic level, one for each bow direction.",
    columns=(
        Column("instrument", pa.string(), "", "violin, viola or cello."),
        Column("string", pa.int8(), "1", "String index, 0 = lowest.", minimum=0, maximum=3),
        Column("semitone", pa.float64(), "semitone",
               "Finger position above the open string.", minimum=0.0, maximum=36.0),
        Column("level", pa.float64(), "1", "Dynamic level, 0 = pppp .. 5 = mf .. 9 = ffff.",
               minimum=0.0, maximum=9.0),
        Column("loudness", pa.float64(), "LUFS",
               "Ungated BS.1770 loudness of the note's steady part (mono).",
               minimum=-120.0, maximum=20.0),
        Column("key", pa.string(), "",
               "Hash of the string physics, bow lanes and engine settings it was measured "
               "with (stale when they change)."),
    ),
)
