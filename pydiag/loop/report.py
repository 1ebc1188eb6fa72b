"""One self-contained HTML page for a comparison: no scripts, no external files.

Sections: the measured and model spectra of each channel with the main kinematic lines
marked, the residual with numbered unexplained peaks, the peak table, the suggested
effects, and the error history. Figures are inline SVG made with matplotlib.
"""

from __future__ import annotations

import html
import io
import tempfile
from pathlib import Path

import numpy as np

from pydiag.io.outputs import write_text
from pydiag.loop.compare import Comparison
from pydiag.loop.history import plot as plot_history

FAMILY_COLOURS = {"mesh": "#c0392b", "pinion": "#2e86c1", "gear": "#27ae60", "bpfo": "#8e44ad",
                  "bpfi": "#d35400", "bsf": "#7f8c8d", "ftf": "#7f8c8d"}
CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 980px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.15em; margin-top: 1.6em; }
table { border-collapse: collapse; font-size: 0.9em; }
td, th { border-bottom: 1px solid #ddd; padding: 3px 10px; text-align: left; }
.num { text-align: right; font-variant-numeric: tabular-nums; }
.confident { font-weight: bold; color: #1a7f37; }
.meta { color: #555; font-size: 0.9em; }
figure { margin: 0.5em 0; } svg { max-width: 100%; height: auto; }
"""


def _svg(fig) -> str:
    buf = io.StringIO()
    fig.savefig(buf, format="svg")
    text = buf.getvalue()
    return text[text.index("<svg"):]


def _spectrum_figure(name: str, spec, markers: list[dict], peaks: list) -> str:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f = np.asarray(spec.freq_hz)
    meas, model = np.asarray(spec.measured), np.asarray(spec.model)
    floor = max(np.sqrt(spec.noise_power), 1e-300)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9.5, 5.6), dpi=100, sharex=True)
    ax1.semilogy(f, np.maximum(meas, floor / 10), lw=0.7, color="#444", label="measured")
    shown = model > floor / 10  # lines the model really produces, not numerical zeros
    ax1.semilogy(f[shown], model[shown], "o", ms=2.5, color="#e67e22", label="model (lines)")
    for m in markers:
        ax1.axvline(m["freq_hz"], color=FAMILY_COLOURS.get(m["family"], "#999"), lw=0.6,
                    alpha=0.5)
    handles = [plt.Line2D([], [], color=c, lw=1.5, label=k) for k, c in FAMILY_COLOURS.items()
               if any(m["family"] == k for m in markers)]
    ax1.legend(handles=ax1.get_legend_handles_labels()[0] + handles, fontsize=7, ncol=4,
               loc="upper right")
    ax1.set_ylabel("amplitude")
    ax1.set_title(f"channel {name}: measured vs model, kinematic lines marked", fontsize=10)
    residual = meas - model
    ax2.plot(f, residual, lw=0.7, color="#1f5fa8")
    ax2.axhline(0, color="#999", lw=0.5)
    for i, p in peaks:
        ax2.annotate(str(i), (p.freq_hz, p.amplitude), textcoords="offset points", xytext=(0, 4),
                     ha="center", fontsize=8, color="#c0392b", fontweight="bold")
        ax2.plot(p.freq_hz, p.amplitude, "v", color="#c0392b", ms=4)
    ax2.set_xlabel("frequency (Hz)")
    ax2.set_ylabel("measured - model")
    fig.tight_layout()
    out = _svg(fig)
    plt.close(fig)
    return out


def write_report(comparison: Comparison, out: str | Path, measurement: str = "",
                 history_rows: list[dict] | None = None, force: bool = False) -> Path:
    """Write the page to ``out`` under the output policy (:mod:`pydiag.io.outputs`)."""
    c = comparison
    numbered = list(enumerate(c.peaks, 1))
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
             f"<title>pydiag compare: {html.escape(Path(c.fmu).name)}</title>"
             f"<style>{CSS}</style></head><body>",
             "<h1>Model vs measurement</h1>",
             f"<p class='meta'>model {html.escape(Path(c.fmu).name)}; measurement "
             f"{html.escape(str(measurement))}; {c.n_periods} fundamental periods, "
             f"{c.bin_hz:.3g} Hz bins; false-alarm rate {c.false_alarm_rate:g}</p>",
             f"<p>Spectral error <b>{c.error:.4f}</b> (Eq. 12 less its noise part; "
             f"{c.error_raw:.4f} raw) on {c.n_error_bins} bins. Fitted parameters: "
             + ", ".join(f"{html.escape(k)} = {v:.4g}" for k, v in c.parameters.items()) + "</p>"]
    for name, spec in c.spectra.items():
        parts.append(f"<h2>Channel {html.escape(name)}</h2><figure>"
                     + _spectrum_figure(name, spec, c.markers,
                                        [(i, p) for i, p in numbered if p.channel == name])
                     + "</figure>")
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
        parts.append("<h2>Residual by family</h2><table><tr><th>channel</th><th>lines</th>"
                     "<th>of the measured energy</th><th>of the residual energy</th></tr>")
        parts += [f"<tr><td>{html.escape(ch)}</td><td>{html.escape(g)}</td>"
                  f"<td class='num'>{100 * v['measured']:.1f} %</td>"
                  f"<td class='num'>{100 * v['residual']:.1f} %</td></tr>"
                  for ch, groups in c.residual_by_family.items() for g, v in groups.items()]
        parts.append("</table>")
    parts.append("<h2>Suggested effects</h2>")
    shown = [s for s in c.suggested_effects if s.score > 0]
    if not shown:
        parts.append("<p>None.</p>")
    else:
        rows = "".join(f"<tr><td class='{'confident' if s.confident else ''}'>"
                       f"{html.escape(s.effect)}</td><td class='num'>{s.score:.2f}</td>"
                       f"<td>{html.escape('confident' if s.confident else s.status)}</td>"
                       f"<td>{html.escape(', '.join(s.competing))}</td>"
                       f"<td>{html.escape('; '.join(s.evidence))}</td></tr>" for s in shown)
        parts.append("<table><tr><th>effect</th><th>score</th><th>held out</th>"
                     "<th>competes with</th><th>evidence</th></tr>" + rows + "</table>")
    if history_rows:
        with tempfile.TemporaryDirectory() as tmp:
            svg = plot_history(history_rows, Path(tmp) / "history.svg").read_text()
        parts.append("<h2>Error history</h2><figure>" + svg[svg.index("<svg"):] + "</figure>")
    parts.append("</body></html>")
    return write_text(out, "\n".join(parts), force)
