"""The contact-diagnostics table: what each string did under the bow, hop by hop.

Written by a render that records the instrument's diagnostics; read by the evaluation and
the automatic teacher (never by the feedback controller).
"""

from __future__ import annotations

import pyarrow as pa

from data_schemas.spec import Column, TableSpec, non_decreasing

CONTACT_DIAGNOSTICS = TableSpec(
    name="contact_diagnostics",
    version="1.0",
    description="Per-hop contact diagnostics of the modal string model, one row per hop per "
                "excited string.",
    columns=(
        Column("time", pa.float64(), "s", "Start of the hop.", minimum=0.0),
        Column("string", pa.int8(), "1", "String index, 0 = lowest.", minimum=0, maximum=3),
        Column("slip_onsets", pa.int32(), "1", "Transitions into slipping during the hop.",
               minimum=0),
        Column("slipping_share", pa.float64(), "1", "Share of the hop's samples slipping.",
               minimum=0.0, maximum=1.0),
        Column("contact_share", pa.float64(), "1",
               "Share of the hop's samples with the bow (or a plucking finger) on the string.",
               minimum=0.0, maximum=1.0),
        Column("mean_slip_speed", pa.float64(), "m/s",
               "Mean |bow velocity - string velocity| over slipping samples.", minimum=0.0),
        Column("sounding_period", pa.float64(), "s",
               "Median interval between slip onsets (earlier hops' last onset included); "
               "null when unknown.", nullable=True, minimum=0.0),
        Column("onset_times", pa.list_(pa.float64()), "s",
               "The slip record: time of each slip onset counted in slip_onsets, from the "
               "performance's start, at the instrument's internal sample resolution; null "
               "in tables written before it was recorded.", nullable=True, required=False),
    ),
    checks=(non_decreasing("time"),),
)
