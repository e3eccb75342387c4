"""Sampled runs bow like the rules: each stroke's speed planned on its own, turns limited.

The joined samples of a run must stay on the hair. Scaled as a whole, a run that drifts is
slowed everywhere (:mod:`gesture_db.bow_plan`); with ``[render] plan_strokes = 1`` in the
search settings, :func:`stroke_planner` hands the run's strokes to the rules' bow
distribution (:func:`pipelines.perform.bow_distribution.distribute`, a linear programme:
slowing a stroke to half costs as much as speeding it up 2x, each stroke at most
``[bow] max_speed_scale`` of the rules' configuration faster), which keeps every stroke as
near its sampled speed as the bow allows. :func:`speed_limiter` holds a run's bow to the
arm's acceleration first (``[render] max_acceleration`` on the instruments listed in
``limit_acceleration``; the rules' own :func:`pipelines.perform.bow_speed.limit_acceleration`).
:func:`assembly_options` gathers both with ``[render] contour_cutoff``, the low-pass that
takes the recordings' sensor noise off the contours (:mod:`gesture_db.smooth`).

Examples
--------
>>> from data_schemas.bow import BowBudget
>>> plan = stroke_planner({"bow": {"max_speed_scale": 1.5}}, {"render": {"plan_strokes": 1}})
>>> start, scale = plan(np.array([0.6, 0.1, 0.6, 0.1, 0.6]), np.array([1.0, 0.2, 1.0, 0.2, 1.0]),
...                     np.array([1, -1, 1, -1, 1]), BowBudget(0.65, 0.03), 0.03)
>>> bool(scale.min() > 0.5), bool(scale[1] > 1.0)    # spread, the short up-bows help
(True, True)
>>> stroke_planner({"bow": {"max_speed_scale": 1.5}}, {"render": {"plan_strokes": 0}}) is None
True
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from data_schemas.bow import BowBudget
from gesture_db.bow_plan import StrokePlanner
from pipelines.perform.bow_distribution import distribute
from pipelines.perform.bow_speed import limit_acceleration


def stroke_planner(config: dict[str, Any], search_config: dict[str, Any]
                   ) -> StrokePlanner | None:
    """The planner of sampled runs' strokes, or None (one scale per run).

    Parameters
    ----------
    config : dict
        Rules configuration (``[bow] max_speed_scale``).
    search_config : dict
        Search settings (``[render] plan_strokes``: 1 plans each stroke, 0 scales whole
        runs).

    Returns
    -------
    StrokePlanner or None
    """
    if not search_config.get("render", {}).get("plan_strokes", 0):
        return None
    cap = float(config["bow"]["max_speed_scale"])

    def plan(travel: np.ndarray, duration: np.ndarray, direction: np.ndarray,
             budget: BowBudget, prefer: float) -> tuple[float, np.ndarray]:
        return distribute(travel, duration, direction, budget=budget, max_scale=cap,
                          prefer=prefer)

    return plan


def speed_limiter(search_config: dict[str, Any], instrument: str
                  ) -> Callable[[np.ndarray, np.ndarray], np.ndarray] | None:
    """The acceleration limit on a sampled run's bow, or None (played as sampled).

    Parameters
    ----------
    search_config : dict
        Search settings: ``[render] max_acceleration`` (m/s^2, 0: off) and
        ``limit_acceleration`` (the instruments it applies to).
    instrument : str

    Returns
    -------
    callable or None
        ``(t s, v m/s) -> v``: the bow speed lowered where it changes faster than
        ``max_acceleration`` (:func:`pipelines.perform.bow_speed.limit_acceleration`, the
        rules' own limit, on ``|v|``; the direction kept). It is applied before the
        run's strokes are planned, so a stroke the planner speeds up (at most ``[bow]
        max_speed_scale``) changes speed that much faster.

    Examples
    --------
    >>> limit = speed_limiter({"render": {"max_acceleration": 5.0,
    ...                                   "limit_acceleration": ["violin"]}}, "violin")
    >>> t = np.arange(0.0, 0.1, 0.01)
    >>> limit(t, np.r_[-0.3, -0.2, -0.1, 0.0, 0.1, 0.2, 0.3, 0.3, 0.3, 0.3]).round(2).tolist()
    [-0.15, -0.1, -0.05, 0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3]
    """
    render = search_config.get("render", {})
    most = float(render.get("max_acceleration", 0.0))
    if most <= 0 or instrument not in render.get("limit_acceleration", []):
        return None

    def limit(t: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.sign(v) * limit_acceleration(t, np.abs(v), most)

    return limit


def assembly_options(config: dict[str, Any], search_config: dict[str, Any],
                     instrument: str) -> dict[str, Any]:
    """How a sampled part's runs are assembled: the keywords of ``assemble_actions``.

    Parameters
    ----------
    config : dict
        Rules configuration.
    search_config : dict
        Search settings (``[render] plan_strokes``, ``max_acceleration``,
        ``limit_acceleration`` and ``contour_cutoff``, Hz).
    instrument : str

    Returns
    -------
    dict
        ``planner`` (:func:`stroke_planner`), ``speed_limit`` (:func:`speed_limiter`) and
        ``cutoff`` (the low-pass on the recorded contours, Hz; 0: as recorded).

    Examples
    --------
    >>> opts = assembly_options({"bow": {"max_speed_scale": 1.5}},
    ...                         {"render": {"contour_cutoff": 20.0}}, "viola")
    >>> opts["planner"] is None, opts["speed_limit"] is None, opts["cutoff"]
    (True, True, 20.0)
    """
    return {"planner": stroke_planner(config, search_config),
            "speed_limit": speed_limiter(search_config, instrument),
            "cutoff": float(search_config.get("render", {}).get("contour_cutoff", 0.0))}


__all__ = ["assembly_options", "speed_limiter", "stroke_planner"]
