"""The model-improvement loop's results, as plain data: a comparison of a fitted model with
a measurement, the effects it suggests, an effect's held-out verdict and a row of
discover's ranking. Each goes to JSON through its ``to_dict``."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields
from enum import Enum

from pydiag.gear.peaks import Peak
from pydiag.signal.spectra import Spectrum

#: The least share of the residual above noise on its own lines a confident effect removes.
MIN_EXPLAINED = 0.5


class Status(str, Enum):
    """Where a suggested effect stands; its sentence (``message``) says why."""

    NOT_VALIDATED = "not validated"  # held-out validation has not looked at it
    NOT_TRIED = "not tried"  # nothing of it to fit or to explain
    IN_MODEL = "already in the model"
    FAILED = "failed"  # its model could not be built or fitted
    NOT_CONFIRMED = "not confirmed"  # held out, no better than noise
    PARTIAL = "partial"  # beats noise, explains under MIN_EXPLAINED of its lines
    SATURATES = "saturates"  # a parameter at a bound of its range
    WORSE = "worse held out"  # explains its lines, but predicts the other half worse
    CONFIRMED = "confirmed"
    OUTCOMPETED = "outcompeted"  # confirmed, but a competitor explains its lines as well
    DEFERRED = "deferred"  # confirmed, but on a base a stronger effect's absence bends


def labelled(effect: str, stage: str | None) -> str:
    """An effect's key, with the machine's stage it is on when it is one's."""
    return effect if stage is None else f"{effect} on {stage}"


@dataclass
class HeldOut:
    """An effect fitted on half A of the record and scored on half B
    (:mod:`pydiag.loop.held_out`)."""

    effect: str
    z: float  # held-out improvement in standard deviations of noise alone
    threshold: float  # z above this: more than noise alone
    explained: float  # share of the residual above noise on the effect's lines removed (B)
    error_base: float  # noise-corrected Eq. (12) on B, base model
    error_effect: float  # the same with the effect
    parameters: dict[str, float]
    at_bound: list[str] = field(default_factory=list)
    n_periods: int = 0  # periods in each half
    delta_bic: float = 0.0  # on half A, where the effect was fitted
    tried: bool = True  # False: nothing of it to fit or to explain, so it was not (z nan)
    envelope_band_hz: tuple[float, float] | None = None  # scored on this band's envelope
    why_not: str = ""  # why it was not tried, when not for want of residual on its lines
    # the non-synchronous lines of half A it claims, at the frequencies the half shows them
    # ("acc envelope 87.50 Hz" for BPFO 89.62 Hz); an effect claiming one of another's
    # competes with it (:func:`pydiag.loop.competition.rivals`)
    claimed: tuple[str, ...] = ()
    # on B, each bin of its lines, named as ``claimed`` names them: (its term of the test
    # statistic, the base's excess there), so competitors can be set side by side
    line_terms: dict[str, tuple[float, float]] = field(default_factory=dict, repr=False)

    @property
    def significant(self) -> bool:
        return self.tried and self.z > self.threshold

    @property
    def predicts_better(self) -> bool:
        """Whether the model with it predicts half B better than the base: its held-out
        error falls. z asks only whether the change it makes is more than half A's noise;
        a change the right way that overshoots, or that bends lines it does not claim,
        passes that and still predicts B worse."""
        return self.error_effect < self.error_base

    @property
    def confirmed(self) -> bool:
        """Whether the held-out test confirms the effect: significant, explaining enough of
        its lines, inside its bounds, predicting half B better. Confident is more: confirmed
        and no competitor explaining its lines as well (:mod:`pydiag.loop.competition`), a
        verdict of a suggestion or a discovery, not of a test alone."""
        return (self.significant and self.explained >= MIN_EXPLAINED and not self.at_bound
                and self.predicts_better)

    @property
    def status(self) -> Status:
        if not self.tried:
            return Status.NOT_TRIED
        if not self.significant:
            return Status.NOT_CONFIRMED
        if self.explained < MIN_EXPLAINED:
            return Status.PARTIAL
        if self.at_bound:
            return Status.SATURATES
        return Status.CONFIRMED if self.predicts_better else Status.WORSE

    @property
    def message(self) -> str:
        """The verdict in a sentence, with the band of the envelope it was scored on."""
        if self.envelope_band_hz is None:
            return self._message
        low, high = self.envelope_band_hz
        return f"{self._message} [on the envelope of {low:.0f}-{high:.0f} Hz]"

    @property
    def _message(self) -> str:
        status = self.status
        if status is Status.NOT_TRIED:
            return f"{status.value}: " + (self.why_not or (
                "none of the bins the test scores (the synchronous lines, the peaks of the "
                "fitted half) is one of its lines: no residual to explain"))
        if status is Status.NOT_CONFIRMED:
            return (f"not confirmed: held out, it lowers the error by no more than noise "
                    f"would (z {self.z:.1f} <= {self.threshold:.1f})")
        if status is Status.PARTIAL:
            return (f"partial: held out, it explains {100 * max(self.explained, 0):.0f} % of "
                    "the residual on its lines; the model form there may be wrong")
        if status is Status.SATURATES:
            return (f"the effect saturates ({', '.join(self.at_bound)} at a bound): its range "
                    "or the model form is wrong")
        if status is Status.WORSE:
            return (f"worse held out: it explains {100 * self.explained:.0f} % of the residual "
                    "on its lines, but the model with it predicts the other half worse (error "
                    f"{self.error_base:.3f} -> {self.error_effect:.3f}): it overshoots, or "
                    "moves lines it does not claim")
        return (f"confirmed held out (z {self.z:.1f}, explains {100 * self.explained:.0f} % "
                "of the residual on its lines)")

    def explained_on(self, lines) -> float:
        """The share of the base's residual above noise it removes on B on ``lines`` (keys
        of :attr:`line_terms`); nan when those lines have none."""
        fall = sum(self.line_terms[k][0] for k in lines if k in self.line_terms)
        excess = sum(self.line_terms[k][1] for k in lines if k in self.line_terms)
        return fall / excess if excess > 0 else math.nan

    def to_dict(self) -> dict:
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "line_terms"}
        return {**out, "status": self.status.value, "significant": self.significant,
                "confirmed": self.confirmed}


@dataclass
class Suggestion:
    """A catalogue effect as a record sees it: what ``compare`` suggests (the residual
    points to it) and what ``discover`` ranks (it was tried held out) alike.

    ``score``: the share of the unexplained peak energy its signature covers (0 where the
    residual was not asked: a discover row); ``evidence``: the lines that say so;
    ``status`` and ``message`` say where it stands; ``held_out``: its held-out verdict (None:
    not tried); ``confident`` only once held-out validation confirmed it and no competitor
    explains its lines as well; ``competing``: the effects whose signatures claim some of
    the same peaks; ``stage``: the stage of a machine's model it goes on (None: the model's
    own pair); ``n_parameters``: the parameters it declares (its hint may fit fewer);
    ``elapsed_s``: the wall time of its build, fit and test (a discover row's)."""

    effect: str
    score: float = 0.0
    evidence: list[str] = field(default_factory=list)
    status: Status = Status.NOT_VALIDATED
    message: str = Status.NOT_VALIDATED.value
    confident: bool = False
    competing: list[str] = field(default_factory=list)
    held_out: HeldOut | None = None
    stage: str | None = None
    n_parameters: int = 0
    elapsed_s: float = 0.0

    @property
    def label(self) -> str:
        """Its effect, with the stage it goes on: "gear_tooth_fault on output stage"."""
        return labelled(self.effect, self.stage)

    @property
    def shown(self) -> bool:
        """Worth a line in a report: the residual points to it, or it was tried held out
        (an effect scored on an envelope may have no score in the spectrum)."""
        return self.score > 0 or self.held_out is not None

    @property
    def z(self) -> float:
        """Held-out z; nan when it was not fitted (``-inf`` when it failed)."""
        if self.status is Status.FAILED:
            return -math.inf
        return self.held_out.z if self.held_out and self.held_out.tried else math.nan

    def to_dict(self) -> dict:
        """Plain data, as compare reports a suggestion."""
        return {"effect": self.effect, "score": self.score, "evidence": self.evidence,
                "status": self.status.value, "message": self.message,
                "confident": self.confident, "competing": self.competing,
                "held_out": self.held_out.to_dict() if self.held_out else None,
                "stage": self.stage}

    def ranking_row(self) -> dict:
        """Plain data, as discover ranks an effect: a number it does not have (not tried,
        failed) is None."""
        h = self.held_out if self.held_out and self.held_out.tried else None
        def number(v: float | None) -> float | None:
            return None if v is None or not math.isfinite(v) else float(v)
        reduction = (1 - h.error_effect / h.error_base if h and h.error_base > 0 else None)
        return {"effect": self.effect, "stage": self.stage, "status": self.status.value,
                "message": self.message,
                "z": number(h.z if h else None),
                "delta_bic": number(h.delta_bic if h else None),
                "error": number(h.error_effect if h else None),
                "error_reduction": number(reduction),
                "added_parameters": len(h.parameters) if h else self.n_parameters,
                "parameters": dict(h.parameters) if h else {},
                "confident": self.confident, "elapsed_s": self.elapsed_s,
                "held_out": h.to_dict() if h else None}


@dataclass
class Comparison:
    fmu: str
    error: float  # noise-corrected Eq. (12) on the comparison bins
    error_raw: float  # the same without the noise correction
    parameters: dict[str, float]
    peaks: list[Peak]
    suggested_effects: list[Suggestion]
    false_alarm_rate: float
    n_periods: int
    duration_s: float  # of the record analysed: n_periods fundamental periods
    bin_hz: float
    n_error_bins: int
    fit_error: float | None = None
    gains: dict[str, float] = field(default_factory=dict)  # model -> measurement, per channel
    # channel -> the measured spectrum on the featurizer's frequencies (its noise power
    # beside it), and the model's there
    spectra: dict[str, Spectrum] = field(default_factory=dict)
    model_spectra: dict[str, Spectrum] = field(default_factory=dict)
    markers: list[dict] = field(default_factory=list)  # main kinematic lines, for plots
    # channel -> group -> {"measured": share of sum R^2, "residual": share of sum (R-S)^2}
    residual_by_family: dict[str, dict[str, dict[str, float]]] = field(default_factory=dict)

    def to_dict(self, with_spectra: bool = False) -> dict:
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d["peaks"] = [asdict(p) for p in self.peaks]
        d["suggested_effects"] = [s.to_dict() for s in self.suggested_effects]
        d.pop("model_spectra")
        if with_spectra:
            d["spectra"] = {c: {"freq_hz": s.freq_hz.tolist(), "measured": s.amplitude.tolist(),
                                "model": self.model_spectra[c].amplitude.tolist(),
                                "noise_power": s.noise_power}
                            for c, s in self.spectra.items()}
        else:
            d.pop("spectra")
            d.pop("markers")
        return d
