"""Text for the terminal: results as tables and lines. Pure functions, no printing."""

from __future__ import annotations

import math

from pydiag.gear.indicators import INDICATORS, IndicatorReport
from pydiag.gear.speed import SpeedEstimate
from pydiag.gear.component import BY_INDICATORS, ComponentVerdict, ModelChange
from pydiag.gear.machine_report import MachineReport
from pydiag.gear.stage_judge import K_SPREAD
from pydiag.diagnose.diagnosis import Diagnosis
from pydiag.loop.history import KeptBaseline, KeptHealthyModel
from pydiag.loop.accumulate import LoopStep
from pydiag.loop.results import Comparison, Status, Suggestion
from pydiag.model.regress import RegressionReport


def format_result(result: Diagnosis, truth: dict | None = None) -> str:
    head = f"{'parameter':<10} {'estimate':>9}" + (f" {'true':>7} {'abs.err':>8}" if truth else "")
    lines = [head, "-" * len(head)]
    for name, value in result.parameters.items():
        row = f"{name:<10} {value:9.4f}"
        if truth and name in truth:
            row += f" {truth[name]:7.3f} {abs(value - truth[name]):8.4f}"
        lines.append(row)
    lines += ["",
              f"fault mode : {result.fault_mode}",
              f"severity   : {result.severity} (tooth: {result.tooth_severity}, "
              f"transmission error: {result.te_severity})"]
    lines += _not_counted(result)
    if result.tooth_contrast is not None:
        lines.append(f"tooth      : contrast {result.tooth_contrast:.3f} (|a_f/a0 - 1|: the faulty "
                     "tooth's stiffness variation against the others')")
    fit = result.fit
    lines += [f"error      : {fit.error:.5f} (Eq. 12, relative, summed over channels)",
              f"evaluations: {fit.evaluations} in {fit.elapsed_s:.1f} s"]
    if fit.failed_evaluations:
        lines.append(f"failed     : {fit.failed_evaluations} simulations, penalised: " + "; ".join(
            f"{n} x {reason}" for reason, n in fit.failure_reasons.items()))
    return "\n".join(lines)


def _not_counted(result: Diagnosis, where: str = "") -> list[str]:
    """A line for each fault group the fit found and the record does not support."""
    return [f"not counted: {where}{t.group.replace('_', ' ')} ({', '.join(t.parameters)}): "
            f"the record does not pin it down (likelihood ratio {t.statistic:.3g} <= "
            f"{t.threshold:.3g}), read as healthy" for t in result.support if not t.supported]


def format_facts(facts: dict) -> str:
    """The record analysed: speed, periods, seconds, channel gains."""
    lines = []
    if facts.get("stage"):
        lines.append(f"stage      : {facts['stage']}")
    if facts.get("model"):
        lines.append(f"model      : {facts['model']}")
    if "speed_hz" in facts:
        lines.append(f"speed      : {facts['speed_hz']:.5f} Hz pinion ({60 * facts['speed_hz']:.2f} "
                     f"rpm; nominal {facts['nominal_speed_hz']:.4g} Hz), varies "
                     f"{facts['speed_variation_pct']:.3f} % over the record; "
                     f"{facts['speed_method']}")
    if facts.get("n_periods") is not None:
        lines.append(f"analysed   : {facts['n_periods']} fundamental periods, "
                     f"{facts['duration_s']:.3f} s")
    if facts.get("gains"):
        lines.append("gains      : " + ", ".join(f"{c} x{g:.4g}" for c, g in facts["gains"].items())
                     + (" (model -> measurement: each a gain curve, its value at the first "
                        "mesh harmonic)" if facts.get("gain_curve")
                        else " (model -> measurement level)"))
    return "\n".join(lines)


def format_comparison(c: Comparison, max_peaks: int = 10) -> str:
    lines = [f"error      : {c.error:.5f} (Eq. 12 less its noise part, {c.error_raw:.5f} raw, on "
             f"{c.n_error_bins} bins: synchronous lines and the measurement's peaks; "
             f"{c.n_periods} periods, {c.bin_hz:.3g} Hz bins)",
             "parameters : " + ", ".join(f"{k}={v:.4g}" for k, v in c.parameters.items()),
             f"peaks      : {len(c.peaks)} unexplained above the noise floor "
             f"(false-alarm rate {c.false_alarm_rate:g})"]
    for i, p in enumerate(c.peaks[:max_peaks], 1):
        lines.append(f"  {i:2d}. {p.channel:<5} {p.freq_hz:9.2f} Hz  {p.family:<15} "
                     f"{100 * p.energy_fraction:5.1f} % of the peaks' energy  {p.label}")
    for channel, groups in c.residual_by_family.items():
        lines.append(f"by family  : {channel}: share of the measured / of the residual energy "
                     "/ of the error (its bins)")
        lines += [f"  {g:<18} {100 * v['measured']:5.1f} % / {100 * v['residual']:5.1f} % / "
                  + (f"{100 * v['error']:5.1f} %" if "error" in v else "-")
                  for g, v in groups.items()]
    shown = [s for s in c.suggested_effects if s.shown]
    lines.append("suggested  : " + ("none" if not shown else ""))
    for s in shown:
        flag = f"CONFIDENT, {s.message}" if s.confident else s.message
        lines.append(f"  {s.label:<26} score {s.score:.2f}: {flag}")
        if s.evidence:
            lines.append(f"  {'':<26} {s.evidence[0]}")
        if s.competing:
            lines.append(f"  {'':<26} competes for the same lines with {', '.join(s.competing)}")
    return "\n".join(lines)


def format_discovery(base: Comparison, found: list[Suggestion]) -> str:
    width = max([26] + [len(d.label) for d in found])
    lines = [f"base model error {base.error:.5f}; effects fitted on half the periods, ranked by "
             "how far they lower the error on the other half (z: in noise standard deviations)",
             f"{'rank':>4} {'effect':<{width}} {'z':>8} {'dBIC':>10} {'error':>8} "
             f"{'reduction':>9}  parameters"]
    for i, d in enumerate(found, 1):
        h = d.held_out
        if h is None or not h.tried:
            lines.append(f"{i:4d} {d.label:<{width}} {'-':>8} {'-':>10} {'-':>8} {'-':>9}  "
                         + (d.message if d.status is not Status.FAILED
                            else f"failed: {d.message}"))
            continue
        params = ", ".join(f"{k}={v:.4g}" for k, v in h.parameters.items())
        reduction = 1 - h.error_effect / h.error_base if h.error_base > 0 else 0.0
        lines.append(f"{i:4d} {d.label:<{width}} {h.z:8.1f} {h.delta_bic:10.1f} "
                     f"{h.error_effect:8.4f} {100 * reduction:8.0f}%  {params}")
        lines.append(f"{'':5}{'CONFIDENT' if d.confident else ''} {d.message}".rstrip())
    return "\n".join(lines)


def format_loop_step(step: LoopStep) -> str:
    """One step of ``pydiag loop``: the model, its error, what was accepted after it (a
    step's number is one more than the effects its model has)."""
    model = " + ".join(("base",) + step.effects)
    text = f"step {len(step.effects) + 1}: {model}: error {step.error:.4f}"
    if step.accepted is not None:
        return (f"{text}; accepted {step.accepted} (held out: error {step.held_out_error_base:.4f}"
                f" -> {step.held_out_error_with:.4f}, z {step.z:.1f})")
    suggestions = step.comparison.suggested_effects
    confident = sorted((s for s in suggestions if s.confident), key=lambda s: -s.held_out.z)
    if confident:
        return (f"{text}; stopped at the step limit, confident: "
                + ", ".join(f"{s.label} (z {s.held_out.z:.1f})" for s in confident))
    tried = [f"{s.label}: {s.status.value}" for s in suggestions if s.held_out is not None]
    return f"{text}; nothing confident" + (f" ({'; '.join(tried)})" if tried else "")


def format_history(rows: list[dict]) -> str:
    lines = [f"{'run':>4} {'time (UTC)':<20} {'model':<28} {'fmu sha256':<12} {'error':>8} {'peaks':>5}"]
    for r in rows:
        lines.append(f"{r['id']:4d} {r['time_utc']:<20} {(r['model_name'] or '')[:28]:<28} "
                     f"{r['fmu_sha256'][:12]:<12} {r['error']:8.4f} {r['n_peaks']:5d}")
    return "\n".join(lines)


def format_regression(report: RegressionReport) -> str:
    lines = [f"FAIL {mm.case} {mm.sensor} at {mm.freq_hz:.2f} Hz: golden {mm.golden:.6g}, "
             f"now {mm.actual:.6g} (allowed +-{mm.allowed:.3g})" for mm in report.mismatches]
    status = "PASS" if report.passed else "FAIL"
    lines.append(f"{status}: {report.cases} cases x {len(report.sensors)} sensors, worst deviation "
                 f"{report.worst_relative:.2e} of the largest line (tolerance {report.rtol:.1e})")
    return "\n".join(lines)


def format_indicators(report: IndicatorReport) -> str:
    """One column per channel, one row per indicator, then what the TSA was made of."""
    channels = list(report.indicators)
    lines = [f"{'indicator':<13}" + "".join(f"{c:>14}" for c in channels)]
    for name in INDICATORS:
        lines.append(f"{name:<13}" + "".join(f"{report.indicators[c][name]:>14.5g}"
                                              for c in channels))
    s = report.speed
    lines += ["", f"TSA        : {report.revolutions} revolutions of the {report.shaft} "
              f"(mesh order {report.mesh_order}), {report.samples_per_rev} samples each",
              f"speed      : {s.speed_hz:.5f} Hz pinion ({60 * s.speed_hz:.2f} rpm; nominal "
              f"{s.nominal_hz:.4g} Hz), varies {s.variation_pct:.3f} %; {s.method}",
              f"NA4, NB4   : relative to {report.reference}"]
    return "\n".join(lines)


def _machine_head(name: str, n_stages: int, s: SpeedEstimate) -> list[str]:
    """The machine and the input speed found, how, and how surely."""
    confidence = ("" if s.confidence_db is None
                  else f"; stands {s.confidence_db:.1f} dB over the next candidate")
    return [f"machine    : {name}, {n_stages} stage(s)",
            f"speed      : {s.speed_hz:.5f} Hz input ({60 * s.speed_hz:.2f} rpm; nominal "
            f"{s.nominal_hz:.4g} Hz), varies {s.variation_pct:.3f} %; {s.method}{confidence}"]


def format_machine_report(report: MachineReport) -> str:
    """The speed; where the TSA was taken, a row per shaft (residual energy and indicators,
    first channel's); where the stages were judged, a row per stage's change; where a
    model fitted them, a row per stage's fit and verdict; then a row per component."""
    lines = _machine_head(report.machine.name, len(report.machine.stages), report.speed)
    if report.record is not None:
        lines += _shaft_rows(report)
    if not report.stages:
        lines += ["", "stages     : not judged: give a baseline record of the machine in a "
                  "known healthy state (--baseline)"]
        return "\n".join(lines)
    if report.baselines:
        lines += _verdict_rows(report)
    if report.fitted:
        lines += _fit_rows(report)
    lines += format_components(report.components)
    lines += format_model_changes(report.model_changes)
    lines += ["", f"severity   : {report.severity_scale}"]
    if report.baselines:
        lines.append(f"baselines  : {', '.join(report.baselines)} (healthy spread "
                     f"{report.spread_db:.2f} dB)")
    return "\n".join(lines)


def _shaft_rows(report: MachineReport) -> list[str]:
    """A row per shaft of the record's TSA, and its swing against the baselines'."""
    shafts = report.record.shafts
    swings = any(s.swing_deg is not None for s in shafts)
    lines = ["", f"{'shaft':<14}{'speed Hz':>10}{'turns':>7}{'teeth':>9}  "
             + "  ".join(f"{'resid ' + c:>14}" for c in shafts[0].residual_energy)
             + (f"  {'swing deg':>10}{'vs base':>9}" if swings else "")]
    for shaft in shafts:
        row = (f"{shaft.shaft:<14}{shaft.speed_hz:>10.4f}{shaft.revolutions:>7d}"
               f"{'/'.join(map(str, shaft.teeth)):>9}  "
               + "  ".join(f"{e:>14.4g}" for e in shaft.residual_energy.values()))
        if swings:
            change = report.swing_change_db.get(shaft.shaft)
            row += (f"  {'-' if shaft.swing_deg is None else f'{shaft.swing_deg:.4f}':>10}"
                    f"{'-' if change is None else f'{change:+.1f} dB':>9}")
        lines.append(row)
    if swings:
        lines.append("swing      : of the input's angle (tacho) once a turn of the shaft, "
                     "degrees of the input's turn; not judged")
    return lines


def _verdict_rows(report: MachineReport) -> list[str]:
    """A row per stage: its shafts' change against the baselines, and the verdict."""
    first = report.stages[0].verdict
    fm4 = ("" if first.fm4_threshold is None else
           f"; FM4 {first.fm4_threshold:.2f} names a suspect")
    own = math.isfinite(first.pinion.threshold_db)
    held = (f"each shaft's own: {K_SPREAD:g} x its deviation, scaled by the healthy halves'"
            if own else
            f"{first.threshold_db:.2f} dB = {first.threshold_db / report.spread_db:g} x the "
            f"healthy spread {report.spread_db:.2f} dB")
    lines = ["", f"{'stage':<16}{'teeth':>7}{'mesh Hz':>10}{'pinion dB':>11}{'gear dB':>9}"
             f"{'thr p/g':>12}{'FM4 p/g':>14}  verdict (threshold {held}{fm4})"]
    for st in report.stages:
        v = st.verdict
        verdict = "changed" if v.changed else "healthy"
        if v.suspect:
            verdict += f", {v.suspect} suspect ({v.suspect_by})"
        for role, change in (("pinion", v.pinion), ("gear", v.gear)):
            if change.explained_by:
                verdict += (f"; the {role} shaft's rise is what "
                            f"{' and '.join(change.explained_by)} put on its lines")
        thresholds = (f"{v.pinion.threshold_db:.2f}/{v.gear.threshold_db:.2f}" if own
                      else f"{v.threshold_db:.2f}")
        lines.append(f"{st.name:<16}{f'{st.pinion_teeth}/{st.gear_teeth}':>7}{st.mesh_hz:>10.2f}"
                     f"{v.pinion.change_db:>+11.2f}{v.gear.change_db:>+9.2f}{thresholds:>12}"
                     f"{f'{v.pinion.fm4_change:+.2f}/{v.gear.fm4_change:+.2f}':>14}  {verdict}")
    return lines


def _fit_rows(report: MachineReport) -> list[str]:
    """A row per stage: teeth, mesh, the fit's tooth contrast and TE levels, error, and
    the stage's fault mode, severity and suspect; then what each fit did not count."""
    lines = ["", f"{'stage':<16}{'teeth':>7}{'mesh Hz':>10}{'contrast':>10}{'f_ate':>7}"
             f"{'f_dte':>7}{'error':>8}  {'fault mode':<20}{'severity':<10}suspect"]
    for st in report.stages:
        p = st.fit.parameters
        contrast = st.fit.tooth_contrast
        lines.append(f"{st.name:<16}{f'{st.pinion_teeth}/{st.gear_teeth}':>7}{st.mesh_hz:>10.2f}"
                     f"{contrast if contrast is not None else float('nan'):>10.3f}"
                     f"{p.get(st.prefix + 'f_ate', float('nan')):>7.3f}"
                     f"{p.get(st.prefix + 'f_dte', float('nan')):>7.3f}"
                     f"{st.fit.error:>8.3f}  {st.fault_mode:<20}{st.severity:<10}"
                     f"{st.suspect or '-'}")
    for st in report.stages:
        lines += _not_counted(st.fit, f"{st.name}'s ")
    return lines


def format_components(judged: tuple[ComponentVerdict, ...]) -> list[str]:
    """One line a component, faulty ones first: what it is, its state, who judged it (the
    indicators or the healthy model), the change it was judged by over its threshold, and
    why."""
    if not judged:
        return []
    name = max(30, *(len(v.component.name) + 2 for v in judged))
    shaft = max(10, *(len(v.component.shaft) + 2 for v in judged))
    lines = ["", f"{'component':<{name}}{'kind':<9}{'shaft':<{shaft}}{'state':<12}"
             f"{'judge':<12}{'x thr':>7}  why"]
    for v in judged:
        c = v.component
        margin = "-" if v.margin is None or v.margin != v.margin else f"{v.margin:.2f}"
        lines.append(f"{c.name:<{name}}{c.kind:<9}{c.shaft:<{shaft}}{v.state:<12}"
                     f"{v.judge:<12}{margin:>7}  {v.reason}")
    model = any(v.judge != BY_INDICATORS for v in judged)
    lines.append("x thr      : " + ("the indicators' " if model else "the ")
                 + "largest change of a component's measures over its threshold "
                 f"({K_SPREAD:g} x how much it varies between healthy records)"
                 + (", or the model's (its effect's rise of held-out z, below)" if model else "")
                 + ": above 1, beyond it")
    return lines


def format_model_changes(changes: tuple[ModelChange, ...]) -> list[str]:
    """One line an effect of the machine's healthy model, changed ones first: its stage,
    the part it names, how far its rise of held-out z is over the healthy repeats', and
    each sizing parameter from its healthy value to the record's."""
    if not changes:
        return []
    stage = max(16, *(len(c.stage) + 2 for c in changes))
    lines = ["", f"{'the model':<30}{'stage':<{stage}}{'state':<12}{'x thr':>7}"
             "  what it fitted"]
    for c in changes:
        margin = "-" if c.margin != c.margin else f"{c.margin:.2f}"
        state = c.fault if c.changed else "good"
        sized = ", ".join(f"{name.split('.', 1)[-1]} {a:.3g} -> {b:.3g}"
                          for name, (a, b) in c.values.items())
        named = (f": {', '.join(c.components)}" if c.changed and c.components else
                 f" (its lines are {c.beaten_by}'s)" if c.beaten_by else
                 " (its lines' residual not lower)" if c.margin > 1 and not c.changed else "")
        lines.append(f"{c.effect:<30}{c.stage:<{stage}}{state:<12}{margin:>7}  {sized}{named}")
    lines.append("x thr      : an effect of the healthy model refitted held out, its rise of "
                 f"z over the baseline's against {K_SPREAD:g} x the healthy repeats' rise")
    return lines


def format_healthy_model(kept: KeptHealthyModel, fitted: bool, db: str,
                         grown: KeptHealthyModel | None = None) -> str:
    """Which healthy model a record was judged by: the files it was fitted and held to,
    whether it was fitted now or read as kept in the history ``db``, and where it was
    kept again when the record asked for lacking effects it had not tried on them
    (``grown``)."""
    more = "" if grown is None else (
        f"; with {len(grown.model.held) - len(kept.model.held)} more of its lacking effects "
        f"tried on them, kept again (id {grown.id})")
    held = (f"held to {', '.join(kept.baselines[1:])}" if kept.baselines[1:] else
            "no healthy repeat to hold a record to: the start of its fit")
    return (f"healthy    : the model fitted to {kept.baselines[0]}, {held}; "
            + (f"kept in {db} (id {kept.id})" if fitted else
               f"as kept in {db} on {kept.time_utc} (id {kept.id})") + more)


def format_kept_baselines(name: str, kept: list[KeptBaseline], db: str) -> str:
    """The baselines kept for machine ``name`` in the history ``db``, a row each."""
    if not kept:
        return f"baselines  : none kept for {name} in {db}"
    lines = [f"baselines  : {len(kept)} kept for {name} in {db}", "",
             f"{'id':>4}  {'kept (UTC)':<21}{'input Hz':>10}  record"]
    lines += [f"{b.id:>4}  {b.time_utc:<21}{b.record.speed.speed_hz:>10.4f}  {b.measurement}"
              for b in kept]
    return "\n".join(lines)
