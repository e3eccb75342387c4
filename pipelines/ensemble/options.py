"""``arco render --all-parts`` options for the ensemble: seating, room, master loudness.

Imports nothing heavy (``arco --help`` stays fast); the mix runs in
:func:`pipelines.ensemble.ensemble_output.write_ensemble`.
"""

from __future__ import annotations

import argparse
from typing import Any

from data_schemas.errors import ParameterError


def add_ensemble_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``ensemble`` option group to ``parser``."""
    group = parser.add_argument_group(
        "ensemble (--all-parts)",
        "the parts mixed in stereo as a quartet sits, in a synthesized room, the master "
        "normalised to a loudness; stems OUT-<index>-<instrument>.wav (panned, dry) beside "
        "it; defaults in pipelines/ensemble/ensemble.toml")
    group.add_argument("--pan", metavar="P1,P2,...",
                       help="pan position of each part in score order, -1 left .. 1 right, "
                            "written --pan=-0.7,-0.25,0.25,0.7 (the default)")
    group.add_argument("--room", choices=("hall", "none"),
                       help="synthesized hall (default) or none (dry)")
    group.add_argument("--rt60", type=float, metavar="S",
                       help="reverberation time at 500 Hz-1 kHz in s (default 1.8)")
    group.add_argument("--loudness", type=float, metavar="LUFS",
                       help="integrated loudness of the master, BS.1770 (default -18)")
    group.add_argument("--mix-config", metavar="ENSEMBLE.toml",
                       help="ensemble settings merged over the shipped defaults")


def ensemble_settings(args: argparse.Namespace) -> dict[str, Any]:
    """The ensemble settings: the shipped ones, ``--mix-config``, then the options.

    Examples
    --------
    >>> args = argparse.Namespace(pan="-1,1", room="none", rt60=None, loudness=-23.0,
    ...                           mix_config=None)
    >>> cfg = ensemble_settings(args)
    >>> cfg["seating"]["pans"], cfg["room"]["kind"], cfg["room"]["rt60"], cfg["master"]["loudness"]
    ([-1.0, 1.0], 'none', 1.8, -23.0)
    """
    from pipelines.ensemble.config import check_ensemble, load_ensemble

    config = load_ensemble(getattr(args, "mix_config", None))
    if getattr(args, "pan", None):
        try:
            config["seating"]["pans"] = [float(p) for p in args.pan.split(",")]
        except ValueError:
            raise ParameterError(f"--pan {args.pan}: give numbers separated by commas, "
                                 "e.g. -0.7,-0.25,0.25,0.7") from None
    for value, section, key in ((getattr(args, "room", None), "room", "kind"),
                                (getattr(args, "rt60", None), "room", "rt60"),
                                (getattr(args, "loudness", None), "master", "loudness")):
        if value is not None:
            config[section][key] = value
    check_ensemble(config, source="arco render")
    return config
