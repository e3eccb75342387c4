"""Settings of the listening loop's control law (:class:`ControllerSettings`).

The defaults are written in ``synth/listening/config/listening.toml`` with their provenance;
:mod:`synth.listening.settings_file` reads a user's file of the same form.
"""

from __future__ import annotations

from dataclasses import dataclass

from data_schemas.errors import ParameterError


@dataclass(frozen=True)
class ControllerSettings:
    """Tuning of the control law.

    Attributes
    ----------
    average : int
        Hops of class probabilities averaged (Vivi's later code averages 4 hops of
        classes; longer averages delay the law and make a fast step overshoot).
    min_speed_share : float
        The law applies only while |v| > this x target velocity.
    jitter : float
        Relative sigma of the Gaussian jitter on the force and velocity played each hop,
        around the controller's own force (not carried on: a random walk of 25 % in 3.5 s).
    range_margin : float
        The force stays within the forces judged acceptable in training (the controller's
        own experience) widened by this factor each way; 0 = only ``0 <= F <= 50 N``.
    step : float
        Force factor per hop at full confidence (``2 ** (1 / 6)``: a 2x error in 6 hops).
    good_share : float
        No correction while the averaged probability of class 3 is at least this.
    change_hops : int
        Hops after a finger change inside a stroke without the law (the analysis window
        still holds the previous note: measured on viola and cello quartet parts, those hops
        were heard as classes 4-5 and pulled the force down).
    trim : float
        Correcting a planned force: the factor stays within ``1 / trim .. trim`` (0: off).
    trim_up : float
        Correcting a planned force: the factor's upper bound instead of ``trim`` (0: ``trim``;
        1: the law only lightens). On the instrument model more force did not end multiple
        slipping once it had set in; lightening only helped feedback on the tuning set, not
        on the held-out protocol (the README, "The law only lightens").
    sure : float
        No correction while neither side ("too little": classes 1-2, "too much": 4-5)
        holds at least this probability (0: off).
    grace_hops : int
        Hops after a stroke starts during which the controller listens but neither averages
        nor applies the law (25 hops, 145 ms: the bow's ramp to 0.33 m/s at 5 m/s^2, one
        analysis window and the median attack), so the attack transient does not pull the
        force away. Measured on the 30 s scale of ``bench/feedback_speed.py``: class 3 on
        87 % of sustained hops at 15 hops, 91.5 % at 25, 91.7 % at 35.
    practised_start : bool
        Correcting a planned force: each stroke starts at its pair's practised factor
        (:attr:`PairModel.start_factor`, learned by ``arco practice``) instead of 1.
    periodic_gate : float
        No correction while the window's YIN aperiodicity is below this: a periodic sound
        is left alone whatever the classifier says (0: off).
    ease_crossings : float
        Zero crossings per period of the expected pitch that, heard on ``ease_after`` hops
        in a row once the law may act, ease the bow once per stroke
        (:mod:`synth.listening.easing`; 0: off).
    ease_after : int
        Hops in a row with that many crossings before the bow is eased.
    ease_factor : float
        Force factor while eased (multiple slipping ends, Helmholtz motion stays:
        ``bench/regime_switch.py``).
    ease_hops : int
        Hops the bow stays eased (17: 0.1 s at 44.1 kHz).
    """

    average: int = 3
    min_speed_share: float = 0.5
    jitter: float = 0.01
    range_margin: float = 2.0
    grace_hops: int = 25
    step: float = 2.0 ** (1.0 / 6.0)
    good_share: float = 0.5
    change_hops: int = 8
    trim: float = 0.0
    trim_up: float = 0.0
    sure: float = 0.0
    practised_start: bool = False
    periodic_gate: float = 0.0
    ease_crossings: float = 0.0
    ease_after: int = 6
    ease_factor: float = 0.3
    ease_hops: int = 17

    def __post_init__(self) -> None:
        if self.ease_after < 1 or self.ease_hops < 1 or not 0.0 <= self.ease_factor <= 1.0:
            raise ParameterError(f"ease_after={self.ease_after} and ease_hops={self.ease_hops} "
                                 f"must be at least 1 and ease_factor={self.ease_factor} "
                                 f"within 0..1")
        if 0.0 < self.trim_up < 1.0:
            raise ParameterError(f"trim_up={self.trim_up} must be 0 (off) or at least 1: the "
                                 f"factor's upper bound may not lie below the plan")


__all__ = ["ControllerSettings"]
