"""The health timeline of a bench run as an SVG picture, written by hand (no plotting library).

One row for the commander (may arm or not), then one row per driver instance with its health
over simulated time (nominal green, warning amber, critical red), a tick where the probe found
the chip and a cross where the driver reset. In a legacy run, configured instances that nothing
started get a grey row: they are missing and nobody says so. Hovering a segment shows its
reason (SVG ``<title>``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from xml.sax.saxutils import escape

from px4params.vehicle.simbench import RunResult

__all__ = ["COLORS", "render_svg"]

COLORS = {
    "nominal": "#2e7d32",
    "warning": "#f9a825",
    "critical": "#c62828",
    "missing": "#9e9e9e",
}
_LABEL_W = 330
_PLOT_W = 620
_ROW_H = 22
_BAR_H = 14
_TOP = 54
_FAMILY = "font-family='DejaVu Sans, Arial, sans-serif'"
_FONT = f"{_FAMILY} font-size='12'"


def _step(duration: float) -> float:
    """A round axis step giving at most about ten ticks."""
    raw = duration / 10
    power = 10 ** math.floor(math.log10(raw)) if raw > 0 else 1
    for factor in (1, 2, 5, 10):
        if raw <= factor * power:
            return factor * power
    return 10 * power


def render_svg(result: RunResult) -> str:
    """The timeline of ``result`` as a standalone SVG document."""
    duration = result.duration
    rows = 1 + len(result.instances) + len(result.silently_missing)
    height = _TOP + rows * _ROW_H + 56
    width = _LABEL_W + _PLOT_W + 20

    def x(t: float) -> float:
        return _LABEL_W + _PLOT_W * min(max(t, 0.0), duration) / duration

    out: list[str] = [
        f"<svg xmlns='http://www.w3.org/2000/svg' width='{width}' height='{height}' "
        f"viewBox='0 0 {width} {height}'>",
        f"<rect width='{width}' height='{height}' fill='white'/>",
    ]
    verdict = result.verdict
    title = f"{result.mode} boot of {result.bench_label}: {verdict} at {duration:g} s"
    title += f" (seed {result.seed})"
    out.append(
        f"<text x='10' y='22' {_FAMILY} font-size='15' font-weight='bold'>{escape(title)}</text>"
    )
    _legend(out, 10, 40)

    y = _TOP
    # The commander: refused until its first answer, then each change.
    segments = [(0.0, False), *result.arming]
    _label(out, y, "commander", "may arm?")
    for n, (start, ok) in enumerate(segments):
        end = segments[n + 1][0] if n + 1 < len(segments) else duration
        color = COLORS["nominal"] if ok else COLORS["critical"]
        _bar(out, x(start), x(end), y, color, "may arm" if ok else "arming refused")
    y += _ROW_H

    for inst in result.instances:
        _label(out, y, f"{inst.name} ({inst.driver})", inst.location)
        for n, (start, level, reason) in enumerate(inst.timeline):
            end = inst.timeline[n + 1][0] if n + 1 < len(inst.timeline) else duration
            tip = f"{level}: {reason}" if reason else level
            _bar(out, x(start), x(end), y, COLORS[level], f"{start:g}-{end:g} s {tip}")
        for at, what in inst.marks:
            _mark(out, x(at), y, what)
        y += _ROW_H

    for line in result.silently_missing:
        # "ak09916 AK09916#0 on I2C bus 1 address 0x0C: never started, ..."
        who, _, rest = line.partition(" on ")
        driver, _, name = who.partition(" ")
        _label(out, y, f"{name} ({driver})", rest.split(":")[0])
        _bar(out, x(0), x(duration), y, COLORS["missing"], line, dashed=True)
        y += _ROW_H

    _axis(out, y + 6, duration, x)
    out.append("</svg>")
    return "\n".join(out) + "\n"


def _label(out: list[str], y: float, name: str, detail: str) -> None:
    out.append(
        f"<text x='10' y='{y + _BAR_H - 2}' {_FONT}><tspan font-weight='bold'>{escape(name)}"
        f"</tspan> <tspan fill='#555'>{escape(detail)}</tspan></text>"
    )


def _bar(
    out: list[str], x0: float, x1: float, y: float, color: str, tip: str, dashed: bool = False
) -> None:
    if x1 - x0 <= 0:
        return
    style = " fill-opacity='0.35' stroke='#757575' stroke-dasharray='4 3'" if dashed else ""
    out.append(
        f"<rect x='{x0:.2f}' y='{y}' width='{x1 - x0:.2f}' height='{_BAR_H}' fill='{color}'"
        f"{style}><title>{escape(tip)}</title></rect>"
    )


def _mark(out: list[str], x0: float, y: float, what: str) -> None:
    if what == "reset":
        d = f"M{x0 - 4:.2f},{y - 3} l8,8 m0,-8 l-8,8"
        out.append(f"<path d='{d}' stroke='black' stroke-width='2'><title>reset</title></path>")
    else:
        out.append(
            f"<path d='M{x0:.2f},{y - 4} v{_BAR_H + 8}' stroke='black' stroke-width='1.5'>"
            f"<title>{escape('probe found the chip: started')}</title></path>"
        )


def _legend(out: list[str], x0: float, y: float) -> None:
    items = [
        ("nominal", "nominal / may arm"),
        ("warning", "warning"),
        ("critical", "critical / refused"),
        ("missing", "missing, nobody told (legacy)"),
    ]
    for key, text in items:
        out.append(f"<rect x='{x0}' y='{y - 10}' width='12' height='12' fill='{COLORS[key]}'/>")
        out.append(f"<text x='{x0 + 16}' y='{y}' {_FONT}>{escape(text)}</text>")
        x0 += 30 + 7 * len(text)
    out.append(f"<text x='{x0}' y='{y}' {_FONT}>| start   \u00d7 reset</text>")


def _axis(out: list[str], y: float, duration: float, x: Callable[[float], float]) -> None:
    out.append(
        f"<line x1='{_LABEL_W}' y1='{y}' x2='{_LABEL_W + _PLOT_W}' y2='{y}' stroke='black'/>"
    )
    step = _step(duration)
    count = int(duration / step + 1e-9)
    for n in range(count + 1):
        t = n * step
        xt = x(t)
        out.append(f"<line x1='{xt:.2f}' y1='{y}' x2='{xt:.2f}' y2='{y + 5}' stroke='black'/>")
        out.append(f"<text x='{xt:.2f}' y='{y + 18}' {_FONT} text-anchor='middle'>{t:g}</text>")
    out.append(
        f"<text x='{_LABEL_W + _PLOT_W / 2}' y='{y + 36}' {_FONT} text-anchor='middle'>"
        "simulated time (s)</text>"
    )
