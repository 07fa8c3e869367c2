"""Reading today's configuration (migrate/config.py) and what a proposal says about it
(migrate/proposal.py), where test_migrate.py leaves them open. The inputs are written by hand
in QGC's ``.params`` format (QGroundControl's ParameterManager: a ``#`` header, then
``vehicle-id component-id name value type`` separated by TABs) and an airframe's ``param set``
lines."""

from __future__ import annotations

from pathlib import Path

import pytest
from px4params import migrate
from px4params.vehicle import devid

DEVTYPES = "code\tname\n0x09\tDRV_MAG_DEVTYPE_AK09916\n"


@pytest.fixture
def devtypes(tmp_path: Path) -> devid.DevtypeTable:
    path = tmp_path / "devtypes.tsv"
    path.write_text(DEVTYPES)
    return devid.load_table("current", path)


def test_a_params_file_has_no_board_and_the_report_says_so(
    tmp_path: Path, devtypes: devid.DevtypeTable
) -> None:
    path = tmp_path / "vehicle.params"
    path.write_text("# Onboard parameters for Vehicle 1\n1\t1\tSYS_AUTOSTART\t4001\t6\n")
    config = migrate.read_config(path)
    assert (config.hardware, config.release, config.console) == (None, None, None)
    proposal = migrate.migrate(config, table=devtypes)
    assert proposal.board is None
    assert any(
        a.startswith("no board information in a QGC .params: ") for a in proposal.assumptions
    )
    assert "  board: not known\n" in proposal.report()


def test_a_proposal_of_a_configuration_made_by_hand_reports_it() -> None:
    """OldConfig is public: a caller may build one from its own reading (details, skipped
    lines and the rest left out) and have the proposal's report and JSON of it."""
    config = migrate.OldConfig("bench.params", "QGC .params", {"SYS_AUTOSTART": 4001})
    assert (config.details, config.skipped, config.published) == ([], [], [])
    proposal = migrate.Proposal(config, table="current")
    report = proposal.report()
    assert report.startswith("Migration of bench.params (QGC .params, 1 parameters)\n")
    assert "Unchanged: 1 other parameters stay classic parameters" in report
    assert proposal.as_dict()["not_carried"] == []
