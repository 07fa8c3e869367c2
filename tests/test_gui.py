"""``px4params gui`` in a real headless Chromium (Debian's package, driven by Playwright): against
``px4params mavlink serve`` with the example airframe, and offline on a store file. Every test
fails on any console error of the page.

Set ``PX4PARAMS_SCREENSHOTS`` to a folder to keep the screenshots (docs/images has them)."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import px4params
import pytest
from browser import chromium, shot, watched_page
from gui_server import (
    CLI,
    Gui,
    Started,
    env_for,
    gui_on_store,
    gui_on_udp,
    load_store,
    make_store,
    serve,
)
from px4params.store.classic import BUNDLED_CLASSIC


@pytest.fixture
def store_file(tmp_path: Path) -> Path:
    return make_store(tmp_path)


@pytest.fixture
def vehicle(store_file: Path) -> Iterator[Started]:
    served = serve(store_file)
    yield served
    served.stop()


@pytest.fixture
def served_gui(vehicle: Started, store_file: Path) -> Iterator[Gui]:
    page = gui_on_udp(vehicle, store_file.parent)
    yield page
    page.stop()


@pytest.fixture
def gui(served_gui: Gui) -> str:
    """The page's URL with its token, as printed."""
    return served_gui.url


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    with chromium() as launched:
        yield launched


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    with watched_page(browser) as watched:
        yield watched


def _open(page: Any, url: str) -> None:
    page.goto(url)
    page.wait_for_selector("body[data-ready=true]")


def _write_all(page: Any) -> list[str]:
    """Open the review, write every row, and return each row's result text."""
    page.click("#review-open")
    page.wait_for_selector("dialog#review[open]")
    page.click("#review-write")
    page.wait_for_function(
        "[...document.querySelectorAll('#review-table .result')].every(r => r.textContent)"
    )
    results = page.locator("#review-table .result").all_inner_texts()
    page.click("#review-close")
    return results


# -- over MAVLink ----------------------------------------------------------------------------


def test_instances_listed_and_an_address_written(
    gui: str, page: Any, store_file: Path, tmp_path: Path
) -> None:
    _open(page, gui)
    assert page.locator(".instance[data-instance='INA238#0']").is_visible()
    assert page.locator(".instance[data-instance='INA238#1']").is_visible()
    assert "2 of 4 configured" in page.inner_text(".choice[data-parameter='INA238']")
    address = page.locator(".instance[data-instance='INA238#1'] input[data-name='INA238_1C']")
    assert address.input_value() == "0x45"  # @format hex
    address.fill("0x46")
    assert page.inner_text("#pending") == "1"
    page.click("#review-open")
    row = page.locator("#review-table tr[data-name='INA238_1C']")
    assert row.locator(".words").inner_text() == "INA238#1 I2C address: 0x45 → 0x46"
    shot(page, "gui-review.png", tmp_path)
    page.click("#review-write")
    page.wait_for_function("document.querySelector('#review-table .result').textContent !== ''")
    assert row.locator(".result").inner_text() == "acknowledged: 70"
    page.click("#review-close")
    assert load_store(store_file).get("INA238#1.bus.i2c.address") == 0x46  # saved by the vehicle
    assert address.input_value() == "0x46"


def test_out_of_range_is_refused_in_the_page_and_never_sent(
    gui: str, page: Any, store_file: Path, vehicle: Started
) -> None:
    _open(page, gui)
    address = page.locator("input[data-name='INA238_1C']")
    address.fill("300")
    error = page.locator(".instance[data-instance='INA238#1'] .error")
    assert error.inner_text() == "300: above the maximum 0x7F"
    assert page.inner_text("#pending") == "0" and page.locator("#review-open").is_disabled()
    address.fill("0x4G")
    assert error.inner_text() == "0x4G: not an integer (decimal or 0x hex)"
    assert load_store(store_file).get("INA238#1.bus.i2c.address") == 0x45
    vehicle.stop()
    log = vehicle.proc.stdout.read()  # type: ignore[union-attr]
    assert "INA238_1C" not in log  # no write reached the vehicle


def test_switching_the_bus_to_spi_shows_the_spi_fields(gui: str, page: Any) -> None:
    _open(page, gui)
    card = page.locator(".instance[data-instance='INA238#1']")
    assert card.locator("[data-variant='i2c']").is_visible()
    card.locator("select[data-name='INA238_1A']").select_option("1")
    spi = card.locator("[data-variant='spi']")
    labels = spi.locator(".field .label").all_inner_texts()
    assert labels[:2] == ["SPI bus number", "Chip select"] and "SPI mode" in labels
    assert card.locator("[data-variant='i2c']").count() == 0
    assert page.inner_text("#pending") == "1"  # one line: the tag and the SPI fields, as shown


def test_an_instance_added_and_removed(gui: str, page: Any, store_file: Path) -> None:
    _open(page, gui)
    page.click("#add-INA238")
    assert page.locator(".instance[data-instance='INA238#2'].new").is_visible()
    assert _write_all(page) == ["acknowledged: 7"]  # INA238_INST: #0, #1, #2
    page.wait_for_selector(
        ".instance[data-instance='INA238#2']:not(.new) input[data-name='INA238_2C']"
    )
    assert load_store(store_file).instances("INA238") == ["INA238#0", "INA238#1", "INA238#2"]
    page.click(".instance[data-instance='INA238#2'] button.remove")
    assert page.locator(".instance[data-instance='INA238#2'].removed").is_visible()
    assert _write_all(page) == ["acknowledged: 3"]
    assert load_store(store_file).instances("INA238") == ["INA238#0", "INA238#1"]
    page.wait_for_selector(".instance[data-instance='INA238#2']", state="detached")


def test_a_params_file_loads_into_the_review(
    gui: str, page: Any, tmp_path: Path, store_file: Path
) -> None:
    _open(page, gui)
    qgc = tmp_path / "change.params"
    qgc.write_text(
        "# Onboard parameters for Vehicle 1\n#\n# Vehicle-Id\tComponent-Id\tName\tValue\tType\n"
        "1\t1\tINA238_1C\t71\t6\n1\t1\tINA238_0P\t250\t6\n1\t1\tSYS_AUTOSTART\t4001\t6\n"
        "1\t1\tNOT_ON_THIS_VEHICLE\t1\t6\n"
    )
    page.set_input_files("#load", str(qgc))
    page.wait_for_selector("dialog#review[open]")
    names = page.locator("#review-table tbody tr").evaluate_all(
        "rows => rows.map(r => r.dataset.name)"
    )
    assert sorted(names) == ["INA238_0P", "INA238_1C", "SYS_AUTOSTART"]
    assert "NOT_ON_THIS_VEHICLE: the vehicle has no such parameter" in page.inner_text(
        "#review-notes"
    )
    page.click("#review-write")
    page.wait_for_function(
        "[...document.querySelectorAll('#review-table .result')].every(r => r.textContent)"
    )
    results = page.locator("#review-table .result").all_inner_texts()
    assert sorted(results) == ["acknowledged: 250", "acknowledged: 4001", "acknowledged: 71"]
    stored = load_store(store_file)
    assert (stored.get("INA238#1.bus.i2c.address"), stored.get("INA238#0.current")) == (71, 250)
    assert stored.get("SYS_AUTOSTART") == 4001


def test_classic_parameters_as_qgc_lists_them(gui: str, page: Any, store_file: Path) -> None:
    _open(page, gui)
    page.click("button[data-tab='classic']")
    page.fill("#search", "autostart")
    row = page.locator("tr[data-param='SYS_AUTOSTART']")
    assert row.locator(".reboot").inner_text() == "reboot"
    assert not row.evaluate("r => r.classList.contains('modified')")
    row.locator("input").fill("4001")
    assert _write_all(page) == ["acknowledged: 4001"]
    assert row.evaluate("r => r.classList.contains('modified')")  # differs from the default
    row.locator("button").click()  # reset to default
    assert _write_all(page) == ["acknowledged: 0"]
    assert load_store(store_file).get("SYS_AUTOSTART") == 0
    page.fill("#search", "")
    page.check("#modified-only")
    assert page.locator("tr[data-param='SYS_AUTOSTART']").count() == 0


def test_health_of_each_device(gui: str, page: Any, tmp_path: Path) -> None:
    _open(page, gui)
    page.wait_for_selector("#health-table tr[data-instance='INA238#1']", state="attached")
    page.click("button[data-tab='health']")
    row = page.locator("#health-table tr[data-instance='INA238#1']")
    assert row.locator("td").nth(3).inner_text() == "critical"
    assert "lost" in row.locator("td").nth(4).inner_text()
    page.click("button[data-tab='manifest']")
    assert page.locator(".instance[data-instance='INA238#1'] .badge").inner_text() == "critical"


def test_save_as_params_and_airframe(gui: str, page: Any, tmp_path: Path) -> None:
    _open(page, gui)
    with page.expect_download() as download:
        page.click("#save-params")
    text = Path(download.value.path()).read_text()
    assert "1\t1\tINA238_1C\t69\t6" in text
    with page.expect_download() as download:
        page.click("#save-airframe")
    airframe = Path(download.value.path()).read_text()
    assert "param add INA238#1" in airframe and "param set-default INA238#1[4] 69" in airframe
    # the airframe is a real one: it rebuilds the same instances
    target = tmp_path / "rebuilt"
    target.mkdir()
    (target / "saved.airframe").write_text(airframe)
    env = env_for(target)
    subprocess.run(
        [*CLI, "run", "saved.airframe"], env=env, cwd=target, check=True, capture_output=True
    )
    rebuilt = load_store(target / "vehicle.store")
    assert rebuilt.instances("INA238") == ["INA238#0", "INA238#1"]
    assert rebuilt.get("INA238#1.bus.i2c.bus_id") == 2


# -- offline ---------------------------------------------------------------------------------


def test_offline_on_a_store_file(store_file: Path, page: Any) -> None:
    started = gui_on_store(store_file)
    try:
        _open(page, started.url)
        assert "offline store" in page.inner_text("#source")
        page.fill("input[data-name='INA238_0P']", "300")
        assert _write_all(page) == ["acknowledged: 300"]
        page.fill("input[data-name='INA238_0P']", "5000")  # uint10: at most 1023
        assert page.locator(".instance[data-instance='INA238#0'] .error").is_visible()
        page.goto("about:blank")  # leave before the server stops (no reconnecting socket)
    finally:
        started.stop()
    assert load_store(store_file).get("INA238#0.current") == 300
    assert (store_file.parent / "vehicle.store.bak").exists()  # saved atomically, with a backup


def test_state_api_is_json(gui: str, page: Any) -> None:
    _open(page, gui)  # the token URL sets the cookie the API needs
    response = page.request.get(gui.split("?")[0] + "api/state")
    body = json.loads(response.text())
    assert body["mode"] == "mavlink" and body["values"]["INA238_INST"] == 3


def test_a_dynamic_array_gets_items_added_and_removed(tmp_path: Path, page: Any) -> None:
    """No bundled type has a dynamic array: one of our own, offline, through --dsdl."""
    root = tmp_path / "ext" / "arr"
    root.mkdir(parents=True)
    (root / "Things.1.0.dsdl").write_text(
        "# A list of things\n# @max_instances 2\n"
        "uint8[<=3] items\n# The items\n# @max 200\n@sealed\n"
    )
    store = tmp_path / "things.store"
    started = Gui(["--store", str(store), "--dsdl", str(root)], env_for(tmp_path), tmp_path)
    try:
        _open(page, started.url)
        page.click("#add-THINGS")
        assert _write_all(page) == ["acknowledged: 1"]  # THINGS_INST: THINGS#0
        card = page.locator(".instance[data-instance='THINGS#0']")
        length = card.locator("[data-field='items._len']")
        assert "0 of 3" in length.inner_text()
        length.locator("button", has_text="Add").click()
        length.locator("button", has_text="Add").click()
        items = card.locator(".array-items input")
        assert items.count() == 2
        items.nth(0).fill("7")
        items.nth(1).fill("201")  # @max 200
        assert card.locator(".error").inner_text() == "201: above the maximum 200"
        items.nth(1).fill("9")
        assert sorted(_write_all(page)) == ["acknowledged: 2", "acknowledged: 7", "acknowledged: 9"]
        card.locator("[data-field='items._len'] button", has_text="Remove last").click()
        assert _write_all(page) == ["acknowledged: 1"]
        page.goto("about:blank")
    finally:
        started.stop()
    schema = px4params.load_schema([root], include_dronecan=False)
    saved = px4params.Store.load(store, schema, classic=BUNDLED_CLASSIC)
    assert saved.get("THINGS#0")["items"] == [7]


def test_other_sites_cannot_write(gui: str, page: Any, store_file: Path) -> None:
    """A page of another site in the same browser cannot write parameters: a cross-site
    'simple' request (text/plain) is refused, as is any request naming another origin, even
    with the page's cookie."""
    _open(page, gui)
    gui = gui.split("?")[0]
    body = json.dumps({"changes": [{"name": "INA238_1C", "value": 1}]})
    plain = page.request.post(gui + "api/write", data=body, headers={"content-type": "text/plain"})
    assert plain.status == 415
    foreign = page.request.post(
        gui + "api/write",
        data=body,
        headers={"content-type": "application/json", "origin": "http://evil.example"},
    )
    assert foreign.status == 403
    assert load_store(store_file).get("INA238#1.bus.i2c.address") == 0x45
