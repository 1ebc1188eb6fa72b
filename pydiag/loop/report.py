"""One self-contained HTML page for a comparison: interactive plots, no network.

Sections: each channel's measured and model spectra, zoomable, with cursors on the mesh
harmonics, the shaft orders and their mesh sidebands and the bearing lines (hover names a
line and its family), and the residual with numbered unexplained peaks (hover: what each
could be); the residual by family; the peak table; the suggested effects; the error
history across model revisions. The plots are plotly's, its script embedded once in the
page, so the file opens anywhere without a network.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from pydiag.gear.kinematic_map import with_gear_bearing
from pydiag.io.outputs import write_text
from pydiag.loop.residual import RESIDUAL_GROUPS
from pydiag.loop.results import Comparison
from pydiag.signal.spectra import Spectrum

FAMILY_COLOURS = with_gear_bearing({
    "mesh": "#c0392b", "pinion": "#2e86c1", "mesh_sb_pinion": "#5dade2", "gear": "#27ae60",
    "mesh_sb_gear": "#82e0aa", "bpfo": "#8e44ad", "bpfi": "#d35400", "bsf": "#7f8c8d",
    "ftf": "#7f8c8d", "other_shaft": "#b7950b"})
CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.15em; margin-top: 1.6em; }
table { border-collapse: collapse; font-size: 0.9em; }
td, th { border-bottom: 1px solid #ddd; padding: 3px 10px; text-align: left; }
.num { text-align: right; font-variant-numeric: tabular-nums; }
.confident { font-weight: bold; color: #1a7f37; }
.meta { color: #555; font-size: 0.9em; }
"""
PLOT_CONFIG = {"displaylogo": False, "responsive": True, "scrollZoom": True}


def _html(fig, div_id: str) -> str:
    """The figure as a div (plotly's script is in the page's head, once)."""
    return fig.to_html(full_html=False, include_plotlyjs=False, div_id=div_id,
                       config=PLOT_CONFIG)


def _spectrum_figure(name: str, spec: Spectrum, model_spec: Spectrum, markers: list[dict],
                     peaks: list):
    """Measured and model spectra (log) above the residual, x shared: zoom one, both follow."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    f = np.asarray(spec.freq_hz)
    meas, model = spec.amplitude, model_spec.amplitude
    floor = max(np.sqrt(spec.noise_power), 1e-300)
    fig = make_subplots(rows=2, cols=1, shared_xaxes=True, vertical_spacing=0.06,
                        row_heights=[0.62, 0.38])
    fig.add_trace(go.Scatter(x=f, y=np.maximum(meas, floor / 10), name="measured",
                             mode="lines", line=dict(width=1, color="#444"),
                             hovertemplate="%{x:.2f} Hz: %{y:.4g}<extra>measured</extra>"),
                  row=1, col=1)
    shown = model > floor / 10  # lines the model really produces, not numerical zeros
    fig.add_trace(go.Scatter(x=f[shown], y=model[shown], name="model", mode="markers",
                             marker=dict(size=4, color="#e67e22"),
                             hovertemplate="%{x:.2f} Hz: %{y:.4g}<extra>model</extra>"),
                  row=1, col=1)
    # the cursors: a vertical line per kinematic line, topped by a hoverable tick above the
    # spectrum naming the line and its family (one legend entry per family)
    top = 2.0 * float(np.max(meas)) if f.size else 1.0
    for family in dict.fromkeys(m["family"] for m in markers):
        mine = [m for m in markers if m["family"] == family]
        colour = FAMILY_COLOURS.get(family, "#999")
        fig.add_trace(go.Scatter(
            x=[m["freq_hz"] for m in mine], y=[top] * len(mine), name=family, mode="markers",
            legendgroup=family, marker=dict(symbol="triangle-down", size=9, color=colour),
            text=[f"{m['label']} ({family})" for m in mine],
            hovertemplate="%{text}<br>%{x:.2f} Hz<extra></extra>"), row=1, col=1)
        for m in mine:
            fig.add_vline(x=m["freq_hz"], line=dict(color=colour, width=0.6), opacity=0.35,
                          row=1, col=1)
    fig.add_trace(go.Scatter(x=f, y=meas - model, name="measured - model", mode="lines",
                             line=dict(width=1, color="#1f5fa8"),
                             hovertemplate="%{x:.2f} Hz: %{y:.4g}<extra>residual</extra>"),
                  row=2, col=1)
    if peaks:
        fig.add_trace(go.Scatter(
            x=[p.freq_hz for _, p in peaks], y=[p.amplitude for _, p in peaks],
            name="unexplained peaks", mode="markers+text",
            marker=dict(symbol="triangle-down", size=8, color="#c0392b"),
            text=[str(i) for i, _ in peaks], textposition="top center",
            customdata=[f"#{i} {p.label} ({p.family}), {100 * p.energy_fraction:.1f} % of the "
                        "unexplained energy" for i, p in peaks],
            hovertemplate="%{customdata}<br>%{x:.2f} Hz<extra></extra>"), row=2, col=1)
    fig.update_yaxes(type="log", title_text="amplitude", exponentformat="power", row=1, col=1)
    fig.update_yaxes(title_text="measured - model", row=2, col=1)
    fig.update_xaxes(title_text="frequency (Hz)", row=2, col=1)
    fig.update_layout(title=f"channel {name}: measured vs model, kinematic lines marked",
                      height=620, margin=dict(l=60, r=20, t=50, b=50), hovermode="closest",
                      template="plotly_white")
    return fig


def _percent(share: float | None) -> str:
    return "-" if share is None else f"{100 * share:.1f} %"


def _family_figure(by_family: dict[str, dict[str, dict[str, float]]]):
    """Each group's share of the measured and of the residual energy, and of the error,
    per channel."""
    import plotly.graph_objects as go

    fig = go.Figure()
    for channel, groups in by_family.items():
        for what, colour in (("measured", "#95a5a6"), ("residual", "#c0392b"),
                             ("error", "#1f5fa8")):
            if any(what not in groups[g] for g in RESIDUAL_GROUPS):
                continue
            fig.add_trace(go.Bar(
                x=list(RESIDUAL_GROUPS), y=[100 * groups[g][what] for g in RESIDUAL_GROUPS],
                name=f"{channel}: of the {what} energy", offsetgroup=f"{channel}-{what}",
                marker_color=colour, opacity=1.0 if channel == next(iter(by_family)) else 0.6,
                hovertemplate="%{x}: %{y:.1f} %<extra>" + f"{channel}, {what}</extra>"))
    fig.update_layout(barmode="group", height=360, yaxis_title="share, %",
                      margin=dict(l=60, r=20, t=20, b=60), template="plotly_white")
    return fig


def _history_figure(rows: list[dict]):
    import plotly.graph_objects as go

    names = [r.get("model_name") or Path(r["fmu"]).stem for r in rows]
    fig = go.Figure(go.Scatter(
        x=[r["id"] for r in rows], y=[r["error"] for r in rows], mode="lines+markers+text",
        text=names, textposition="top center", line=dict(color="#1f5fa8"),
        hovertemplate="run %{x}: %{text}<br>error %{y:.4f}<extra></extra>"))
    fig.update_layout(height=320, xaxis_title="compare run",
                      yaxis_title="spectral error (Eq. 12, relative)",
                      yaxis_rangemode="tozero", xaxis_dtick=1,
                      margin=dict(l=60, r=20, t=20, b=50), template="plotly_white")
    return fig


def write_report(comparison: Comparison, out: str | Path, measurement: str = "",
                 history_rows: list[dict] | None = None, force: bool = False) -> Path:
    """Write the page to ``out`` under the output policy (:mod:`pydiag.io.outputs`)."""
    from plotly.offline import get_plotlyjs

    c = comparison
    numbered = list(enumerate(c.peaks, 1))
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
             f"<title>pydiag compare: {html.escape(Path(c.fmu).name)}</title>"
             f"<style>{CSS}</style><script>{get_plotlyjs()}</script></head><body>",
             "<h1>Model vs measurement</h1>",
             f"<p class='meta'>model {html.escape(Path(c.fmu).name)}; measurement "
             f"{html.escape(str(measurement))}; {c.n_periods} fundamental periods, "
             f"{c.bin_hz:.3g} Hz bins; false-alarm rate {c.false_alarm_rate:g}</p>",
             f"<p>Spectral error <b>{c.error:.4f}</b> (Eq. 12 less its noise part; "
             f"{c.error_raw:.4f} raw) on {c.n_error_bins} bins. Fitted parameters: "
             + ", ".join(f"{html.escape(k)} = {v:.4g}" for k, v in c.parameters.items()) + "</p>"]
    for k, (name, spec) in enumerate(c.spectra.items()):
        fig = _spectrum_figure(name, spec, c.model_spectra[name], c.markers,
                               [(i, p) for i, p in numbered if p.channel == name])
        parts.append(f"<h2>Channel {html.escape(name)}</h2>"
                     + _html(fig, f"spectrum-{k}"))
    parts.append("<h2>Unexplained peaks</h2>")
    if not c.peaks:
        parts.append("<p>None: the model explains every line above the noise floor.</p>")
    else:
        rows = "".join(f"<tr><td class='num'>{i}</td><td>{html.escape(p.channel)}</td>"
                       f"<td class='num'>{p.freq_hz:.2f}</td><td>{html.escape(p.family)}</td>"
                       f"<td>{html.escape(p.label)}</td><td class='num'>{p.amplitude:.4g}</td>"
                       f"<td class='num'>{100 * p.energy_fraction:.1f} %</td></tr>"
                       for i, p in numbered)
        parts.append("<table><tr><th>#</th><th>channel</th><th>Hz</th><th>family</th>"
                     "<th>line</th><th>excess</th><th>energy</th></tr>" + rows + "</table>")
    if c.residual_by_family:
        parts.append("<h2>Residual by family</h2>"
                     + _html(_family_figure(c.residual_by_family), "residual-by-family"))
        parts.append("<table><tr><th>channel</th><th>lines</th>"
                     "<th>of the measured energy</th><th>of the residual energy</th>"
                     "<th>of the error (its bins)</th></tr>")
        parts += [f"<tr><td>{html.escape(ch)}</td><td>{html.escape(g)}</td>"
                  f"<td class='num'>{100 * v['measured']:.1f} %</td>"
                  f"<td class='num'>{100 * v['residual']:.1f} %</td>"
                  f"<td class='num'>{_percent(v.get('error'))}</td></tr>"
                  for ch, groups in c.residual_by_family.items() for g, v in groups.items()]
        parts.append("</table>")
    parts.append("<h2>Suggested effects</h2>")
    shown = [s for s in c.suggested_effects if s.shown]
    if not shown:
        parts.append("<p>None.</p>")
    else:
        rows = "".join(f"<tr><td class='{'confident' if s.confident else ''}'>"
                       f"{html.escape(s.effect)}</td><td class='num'>{s.score:.2f}</td>"
                       f"<td>{html.escape(('confident: ' if s.confident else '') + s.message)}</td>"
                       f"<td>{html.escape(', '.join(s.competing))}</td>"
                       f"<td>{html.escape('; '.join(s.evidence))}</td></tr>" for s in shown)
        parts.append("<table><tr><th>effect</th><th>score</th><th>held out</th>"
                     "<th>competes with</th><th>evidence</th></tr>" + rows + "</table>")
    if history_rows:
        parts.append("<h2>Error history</h2>"
                     + _html(_history_figure(history_rows), "history"))
    parts.append("</body></html>")
    return write_text(out, "\n".join(parts), force)
