"""Competing effects: at most one is confident among those that claim the same lines, and
only one the record tells apart from them.

Two effects compete when compare found them claiming the same peaks of the whole record,
or when their held-out fits claimed one of the same non-synchronous lines of half A
(:func:`rivals`: joined halves can put two bearing frequencies a few hertz apart on one
bin). A competitor beats a confident effect when it is confident with a larger z, or when
it beat noise too with a z within the test's threshold of the effect's: the record does
not tell them apart, and neither is confident. Unless the lines both claim tell them
apart (:func:`_told_apart`): the effect removes at least MIN_EXPLAINED of the residual
there and the competitor under :data:`TOLD_APART` of that (a faulty tooth's fit, which
leaves a shaft's own orders as they were, against the shaft's lines). Each verdict says
what the two remove on the lines both claim.

An effect whose absence bends the base fit (``Effect.reshapes_base``: a torque ripple, a
transfer path, a swing of a shaft's speed) and that is confident says that the base every
other effect was tried against is bent: their fits may have taken up what it leaves (a
non-synchronous ripple's sidebands leak into the bins of the joined halves). Each
confident effect with a smaller z than the strongest such one is deferred
(:func:`deferred`): it is judged again once that one is in the model, which is the loop's
next step. compare's validation and discover apply these rules, :func:`settle`.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Iterable

from pydiag.loop.held_out import FALSE_ALARM_RATE, threshold
from pydiag.loop.results import MIN_EXPLAINED, HeldOut, Status

#: On the lines two competitors both claim, one that removes less than this share of what
#: the other removes (which removes at least MIN_EXPLAINED there) is told apart from it.
TOLD_APART = 0.5


def settle(held: dict[str, HeldOut], competing: dict[str, list[str]],
           bending: Collection[str] = (), false_alarm_rate: float = FALSE_ALARM_RATE
           ) -> dict[str, tuple[Status, str]]:
    """The confident effects of ``held`` (key -> held-out verdict) that are not confident
    after all, each with its status and the sentence that says why: those a competitor
    beats (outcompeted), and of the others those a stronger effect of ``bending`` defers
    (:func:`deferred`). ``competing``: the effects compare found claiming the same peaks
    as each (``Suggestion.competing``); ``bending``: the effects whose absence bends the
    base (``Effect.reshapes_base``)."""
    confident = {k: h.z for k, h in held.items() if h.confirmed}
    beaten = outcompeted(confident,
                         rivals(competing, {k: h.claimed for k, h in held.items() if h.tried}),
                         {k: h.z for k, h in held.items() if h.significant},
                         threshold(false_alarm_rate), held)
    waiting = deferred({k: z for k, z in confident.items() if k not in beaten}, bending)
    return ({k: (Status.OUTCOMPETED, why) for k, why in beaten.items()}
            | {k: (Status.DEFERRED, why) for k, why in waiting.items()})


def mark_settled(rows: Iterable, verdicts: dict[str, tuple[Status, str]]) -> None:
    """Mark each of ``rows`` (compare's suggestions or discover's rows: ``effect``,
    ``confident``, ``status``, ``message``) that ``verdicts`` (:func:`settle`'s) names as
    not confident, with its status and the sentence that says why."""
    for row in rows:
        if row.effect in verdicts:
            row.confident = False
            row.status, row.message = verdicts[row.effect]


def deferred(confident_z: dict[str, float], bending: Collection[str]) -> dict[str, str]:
    """Of the ``confident_z`` effects (key -> held-out z), those with a smaller z than the
    strongest of them whose absence bends the base (``bending``), each with the sentence
    that says so: they were tried against the bent base (module docstring)."""
    ranked = sorted(confident_z, key=lambda k: -confident_z[k])
    top = next((k for k in ranked if k in bending), None)
    if top is None:
        return {}
    return {k: (f"confirmed held out (z {confident_z[k]:.1f}), but against a base that "
                f"{top}'s absence bends ({top} is confident, z {confident_z[top]:.1f}): "
                f"judged again once {top} is in the model")
            for k in ranked[ranked.index(top) + 1:]}


def rivals(competing: dict[str, list[str]], claimed: dict[str, tuple[str, ...]]
           ) -> dict[str, list[str]]:
    """Each effect's competitors: those compare found claiming the same peaks of the whole
    record (``competing``), and those whose held-out fit claimed one of the same
    non-synchronous lines of the half (``claimed``: key -> :attr:`HeldOut.claimed`). The
    half's spectrum (and an envelope's) is not the one compare names peaks on: joining
    every other period moves a line that is not synchronous (``joined_freq_hz``), so two
    bearing frequencies a few hertz apart can land on one bin."""
    out = {key: list(keys) for key, keys in competing.items()}
    for key, lines in claimed.items():
        for other, theirs in claimed.items():
            if other != key and set(lines) & set(theirs) and other not in out.setdefault(key, []):
                out[key].append(other)
    return out


def outcompeted(confident_z: dict[str, float], competing: dict[str, list[str]],
                significant_z: dict[str, float] | None = None,
                margin: float = threshold(),
                fits: dict[str, HeldOut] | None = None) -> dict[str, str]:
    """At most one confident effect among those that claim the same lines, and only one
    the record tells apart from them: of the ``confident_z`` effects (key -> held-out z),
    those a competitor (``competing``) beats, each with the sentence that says so. A
    competitor beats an effect when it is confident with a larger z, or when it beat noise
    held out (``significant_z``: key -> z of every such effect, confident or not) with a z
    within ``margin`` of the effect's: two effects that explain the same lines about as
    well are not told apart by this record, and neither is confident. ``fits`` (key ->
    :class:`HeldOut`, when known): each sentence also gives the share of the residual each
    of the two removes on the lines both claim, and a competitor that is not confident
    and that those lines tell apart from the effect (:func:`_told_apart`) does not come
    close to it: its z was earned on its other lines."""
    kept: list[str] = []
    beaten = {}
    near = significant_z or {}
    for key in sorted(confident_z, key=lambda k: -confident_z[k]):
        rival = next((k for k in kept if k in competing.get(key, ())), None)
        close = next((k for k in sorted(near, key=lambda k: -near[k])
                      if k != key and k in competing.get(key, ())
                      and near[k] > confident_z[key] - margin
                      and not _told_apart(key, k, fits)), None)
        if rival is not None:
            beaten[key] = (f"competes with {rival} for the same lines, which explains them "
                           f"better held out (z {confident_z[rival]:.1f} > "
                           f"{confident_z[key]:.1f}){_on_shared_lines(key, rival, fits)}")
        elif close is not None:
            how = ("about as well" if near[close] < confident_z[key] + margin else
                   "at least as well")
            beaten[key] = (f"competes with {close} for the same lines, which explains them "
                           f"{how} held out (z {near[close]:.1f} against "
                           f"{confident_z[key]:.1f}{_on_shared_lines(key, close, fits)}): "
                           "this record does not tell them apart")
        else:
            kept.append(key)
    return beaten


def _shared_lines(key: str, other: str, fits: dict[str, HeldOut] | None
                  ) -> tuple[int, float, float] | None:
    """(how many lines ``key`` and ``other`` both claim, the share of the residual there
    each removes), or None when not known or neither has residual there."""
    if not fits or key not in fits or other not in fits:
        return None
    shared = set(fits[key].line_terms) & set(fits[other].line_terms)
    mine, theirs = fits[key].explained_on(shared), fits[other].explained_on(shared)
    if not shared or math.isnan(mine) or math.isnan(theirs):
        return None
    return len(shared), mine, theirs


def _told_apart(key: str, other: str, fits: dict[str, HeldOut] | None) -> bool:
    """Whether the lines ``key`` and ``other`` both claim tell them apart: ``key`` removes
    at least MIN_EXPLAINED of the residual there (what a confident effect removes of its
    own lines) and ``other`` less than :data:`TOLD_APART` of what ``key`` removes (a shaft's
    own lines, which a faulty tooth's fit leaves as they were). False when not known."""
    both = _shared_lines(key, other, fits)
    return both is not None and both[1] >= MIN_EXPLAINED and both[2] < TOLD_APART * both[1]


def _on_shared_lines(key: str, other: str, fits: dict[str, HeldOut] | None) -> str:
    """"; on the 9 lines both claim it removes 69 % of the residual, housing 55 %", or ""."""
    both = _shared_lines(key, other, fits)
    if both is None:
        return ""
    n, mine, theirs = both
    lines = f"the {n} lines" if n > 1 else "the one line"
    return (f"; on {lines} both claim it removes {100 * max(mine, 0):.0f} % "
            f"of the residual, {other} {100 * max(theirs, 0):.0f} %")
