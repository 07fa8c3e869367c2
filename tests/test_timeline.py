"""The health timeline picture (``vehicle/timeline.py``) of a bench run written here by hand: what
the picture must say is read off the run (its docstring's rules: a commander row, one row per
instance, green/amber/red by health, a tick where the probe found the chip, a cross where the
driver reset, a grey dashed row per instance nothing started, the reason on hover), and the
picture is read back as SVG (SVG 1.1: ``rect``, ``path``, ``title`` children as tooltips)."""

from __future__ import annotations

import itertools
import xml.etree.ElementTree as ET

import pytest
from px4params.vehicle.simbench import InstanceResult, RunResult
from px4params.vehicle.timeline import COLORS, render_svg

NS = "{http://www.w3.org/2000/svg}"
GREEN, AMBER, RED, GREY = "#2e7d32", "#f9a825", "#c62828", "#9e9e9e"
LEGEND_WORDS = (
    "nominal / may arm",
    "warning",
    "critical / refused",
    "missing, nobody told (legacy)",
)


def _run(duration: float = 10.0, **changes) -> RunResult:
    ina = InstanceResult(
        name="INA238#0", driver="ina238", parameter="PWR_MON_0", kind="i2c", bus_id=1,
        address=0x45,
        timeline=[(0.0, "critical", "not found: no ACK"), (2.0, "nominal", ""),
                  (6.0, "warning", "checksum <error> & retry")],
        marks=[(2.0, "start"), (6.0, "reset")],
    )  # fmt: skip
    fields = {
        "mode": "manifest", "seed": 7, "duration": duration, "bench": "b&b", "instances": [ina],
        "may_arm": False, "failures": [], "arming": [(2.0, True), (6.0, False)],
        "silently_missing": [
            "ak09916 AK09916#0 on I2C bus 1 address 0x0C: never started, nobody said so"
        ],
    }  # fmt: skip
    fields.update(changes)
    return RunResult(**fields)


def _svg(result: RunResult) -> ET.Element:
    return ET.fromstring(render_svg(result))


def _bars(root: ET.Element) -> list[ET.Element]:
    """The segments: the rectangles with a tooltip (the background and the legend have none)."""
    return [r for r in root.iter(f"{NS}rect") if r.find(f"{NS}title") is not None]


def _span(rect: ET.Element) -> tuple[float, float]:
    x = float(rect.get("x"))
    return x, x + float(rect.get("width"))


def _axis(root: ET.Element) -> tuple[float, float, float]:
    """The time axis: the one long horizontal line (x from, x to, y)."""
    (line,) = [ln for ln in root.iter(f"{NS}line") if ln.get("y1") == ln.get("y2")
               and float(ln.get("x2")) - float(ln.get("x1")) > 100]  # fmt: skip
    return float(line.get("x1")), float(line.get("x2")), float(line.get("y1"))


def test_timeline_colors_are_the_levels_of_health() -> None:
    assert COLORS == {"nominal": GREEN, "warning": AMBER, "critical": RED, "missing": GREY}


def test_timeline_picture_is_a_whole_svg_document() -> None:
    text = render_svg(_run())
    assert text.endswith("</svg>\n")
    root = ET.fromstring(text)
    assert root.tag == f"{NS}svg"
    width, height = float(root.get("width")), float(root.get("height"))
    assert root.get("viewBox") == f"0 0 {root.get('width')} {root.get('height')}"
    background = root.find(f"{NS}rect")
    assert (background.get("width"), background.get("height"), background.get("fill")) == (
        root.get("width"),
        root.get("height"),
        "white",
    )
    # Everything drawn lies inside the picture, the axis' caption included.
    for element in root.iter():
        for attribute in ("x", "x1", "x2"):
            if element.get(attribute) is not None:
                assert 0 <= float(element.get(attribute)) <= width, (element.tag, element.attrib)
        for attribute in ("y", "y1", "y2"):
            if element.get(attribute) is not None:
                assert 0 <= float(element.get(attribute)) <= height, (element.tag, element.attrib)
    x0, x1, axis_y = _axis(root)
    caption = [t for t in root.iter(f"{NS}text") if t.text == "simulated time (s)"]
    assert len(caption) == 1 and float(caption[0].get("y")) > axis_y
    assert float(caption[0].get("x")) == (x0 + x1) / 2 and caption[0].get("text-anchor") == "middle"
    assert float(caption[0].get("y")) + 12 <= height  # a line of 12-point text below it fits


def test_timeline_title_says_mode_bench_verdict_duration_and_seed() -> None:
    texts = ["".join(t.itertext()) for t in _svg(_run()).iter(f"{NS}text")]
    assert texts[0] == "manifest boot of b&b: arming refused at 10 s (seed 7)"
    texts = ["".join(t.itertext()) for t in _svg(_run(2.5, may_arm=True)).iter(f"{NS}text")]
    assert texts[0] == "manifest boot of b&b: may arm at 2.5 s (seed 7)"


def test_timeline_rows_commander_then_instances_then_the_missing() -> None:
    root = _svg(_run())
    x0, x1, axis_y = _axis(root)
    assert x1 - x0 > 0
    rows: dict[float, list[tuple[float, float, str, str]]] = {}
    for rect in _bars(root):
        start, end = _span(rect)
        rows.setdefault(float(rect.get("y")), []).append(
            (start, end, rect.get("fill"), rect.find(f"{NS}title").text)
        )
    ys = sorted(rows)
    assert len(ys) == 3 and ys[-1] < axis_y
    heights = {float(r.get("height")) for r in _bars(root)}
    assert len(heights) == 1 and heights.pop() <= ys[1] - ys[0] == ys[2] - ys[1]  # no overlap

    def at(t: float) -> float:
        return x0 + (x1 - x0) * t / 10

    # Each row tiles the time axis: segments one after the other, from 0 to the run's end.
    commander, ina, missing = (rows[y] for y in ys)
    expected = [(at(0), at(2), RED, "arming refused"), (at(2), at(6), GREEN, "may arm"),
                (at(6), at(10), RED, "arming refused")]  # fmt: skip
    assert [(pytest.approx(a), pytest.approx(b), c, d) for a, b, c, d in commander] == expected
    expected = [
        (at(0), at(2), RED, "0-2 s critical: not found: no ACK"),
        (at(2), at(6), GREEN, "2-6 s nominal"),
        (at(6), at(10), AMBER, "6-10 s warning: checksum <error> & retry"),
    ]
    assert [(pytest.approx(a), pytest.approx(b), c, d) for a, b, c, d in ina] == expected
    line = "ak09916 AK09916#0 on I2C bus 1 address 0x0C: never started, nobody said so"
    assert [(pytest.approx(a), pytest.approx(b), c, d) for a, b, c, d in missing] == [
        (at(0), at(10), GREY, line)
    ]
    # Only the missing row is dashed and faint.
    dashed = [r for r in _bars(root) if r.get("stroke-dasharray")]
    assert [(r.get("stroke-dasharray"), r.get("fill-opacity")) for r in dashed] == [("4 3", "0.35")]
    # Each row's label, on the row: name (driver), then where it is.
    labels = {}
    for text in root.iter(f"{NS}text"):
        spans = [s.text for s in text.iter(f"{NS}tspan")]
        if spans:
            labels[spans[0]] = (spans[1], float(text.get("y")))
    assert list(labels) == ["commander", "INA238#0 (ina238)", "AK09916#0 (ak09916)"]
    assert labels["AK09916#0 (ak09916)"][0] == "I2C bus 1 address 0x0C"
    assert labels["commander"][0] == "may arm?"
    for y, (_, label_y) in zip(ys, labels.values(), strict=True):
        assert y < label_y <= y + 14  # the text's baseline within its bar's height


def test_timeline_marks_where_the_probe_found_the_chip_and_the_driver_reset() -> None:
    root = _svg(_run())
    x0, x1, _ = _axis(root)
    ina_y = sorted({float(r.get("y")) for r in _bars(root)})[1]
    paths = {p.find(f"{NS}title").text: p.get("d") for p in root.iter(f"{NS}path")}
    assert set(paths) == {"probe found the chip: started", "reset"}
    start = x0 + (x1 - x0) * 2 / 10
    assert paths["probe found the chip: started"] == f"M{start:.2f},{ina_y - 4:g} v22"
    # The reset: a cross (two strokes of 8 by 8) centred on the reset's time.
    reset = x0 + (x1 - x0) * 6 / 10
    assert paths["reset"] == f"M{reset - 4:.2f},{ina_y - 3:g} l8,8 m0,-8 l-8,8"


def test_timeline_axis_ticks_at_a_round_step() -> None:
    # About ten ticks at 1, 2 or 5 times a power of ten, from 0 to the run's end.
    for duration, ticks in [
        (10, [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10]),
        (3, [0, 0.5, 1, 1.5, 2, 2.5, 3]),
        (30, [0, 5, 10, 15, 20, 25, 30]),
        (12, [0, 2, 4, 6, 8, 10, 12]),
        (100, [0, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100]),
        (0.5, [0, 0.05 * 1, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5]),
        (95, [0, 10, 20, 30, 40, 50, 60, 70, 80, 90]),
        (21, [0, 5, 10, 15, 20]),  # step 2 would make 10.5 steps: more than ten
    ]:
        root = _svg(_run(duration, instances=[], silently_missing=[], arming=[]))
        x0, x1, axis_y = _axis(root)
        labels = [t for t in root.iter(f"{NS}text") if t.get("text-anchor") == "middle"]
        labels = [t for t in labels if t.text != "simulated time (s)"]
        assert [float(t.text) for t in labels] == pytest.approx(ticks), duration
        for t in labels:
            expected = x0 + (x1 - x0) * float(t.text) / duration  # written to 1/100 px
            assert float(t.get("x")) == pytest.approx(expected, abs=0.005)
            assert float(t.get("y")) > axis_y
        marks = [ln for ln in root.iter(f"{NS}line") if ln.get("x1") == ln.get("x2")]
        assert [float(m.get("x1")) for m in marks] == [float(t.get("x")) for t in labels]
        assert all((float(m.get("y1")), float(m.get("y2"))) == (axis_y, axis_y + 5) for m in marks)


def test_timeline_times_outside_the_run_are_drawn_at_its_ends() -> None:
    # A segment from before 0 or past the end is clipped to the plot; one of no length is left out.
    result = _run(4.0, arming=[(-1.0, True), (9.0, False)])
    result.instances[0].timeline = [(0.0, "nominal", ""), (0.0, "critical", "x")]
    result.instances[0].marks = []
    root = _svg(result)
    x0, x1, _ = _axis(root)
    commander_y = min(float(r.get("y")) for r in _bars(root))
    commander = [(r.find(f"{NS}title").text, _span(r)) for r in _bars(root)
                 if float(r.get("y")) == commander_y]  # fmt: skip
    assert [(tip, pytest.approx(a), pytest.approx(b)) for tip, (a, b) in commander] == [
        ("may arm", x0, x1)
    ]
    tips = [r.find(f"{NS}title").text for r in _bars(root)]
    assert "0-0 s nominal" not in tips and "0-4 s critical: x" in tips


def test_timeline_legend_names_each_color() -> None:
    root = _svg(_run())
    legend = [r for r in root.iter(f"{NS}rect") if r.get("width") == "12"]
    assert [r.get("fill") for r in legend] == [GREEN, AMBER, RED, GREY]
    follows = [t for t in root.iter(f"{NS}text") if t.get("y") == "40"]
    assert [t.text for t in follows] == [
        "nominal / may arm", "warning", "critical / refused", "missing, nobody told (legacy)",
        "| start   \u00d7 reset",
    ]  # fmt: skip
    # Each swatch is left of its words, and the entries do not overlap (7 px a character).
    for swatch, words in zip(legend, follows, strict=False):
        assert float(swatch.get("x")) + 12 < float(words.get("x"))
        assert float(swatch.get("y")) + 12 > float(words.get("y")) - 12
    for words, after in itertools.pairwise(follows):
        assert float(words.get("x")) + 7 * len(words.text) <= float(after.get("x"))


def test_timeline_legend_swatch_sits_on_the_row_of_its_words() -> None:
    # SVG text's y is its baseline: a line of font-size f fills the em box from y - f down to
    # y. A legend's swatch belongs to its words when its middle lies in that box (a swatch
    # below the baseline reads as the key of the row beneath).
    root = _svg(_run())
    legend = [r for r in root.iter(f"{NS}rect") if r.get("width") == "12"]
    words = [t for t in root.iter(f"{NS}text") if t.text in LEGEND_WORDS]
    assert len(legend) == len(words) == 4
    for swatch, text in zip(legend, words, strict=True):
        middle = float(swatch.get("y")) + float(swatch.get("height")) / 2
        baseline, size = float(text.get("y")), float(text.get("font-size"))
        assert baseline - size <= middle <= baseline, (text.text, middle, baseline)


def test_timeline_keeps_a_glitch_shorter_than_a_pixel() -> None:
    # A critical moment of 5 ms in a 10 s run is less than a pixel wide: it is still drawn (a
    # broken sensor is never silent), only segments of no length are left out.
    result = _run()
    result.instances[0].timeline = [(0.0, "nominal", ""), (5.0, "critical", "x"),
                                    (5.005, "nominal", "")]  # fmt: skip
    glitch = [
        r for r in _bars(_svg(result)) if r.find(f"{NS}title").text == "5-5.005 s critical: x"
    ]
    assert len(glitch) == 1 and 0 < float(glitch[0].get("width")) < 1
    assert glitch[0].get("fill") == RED
