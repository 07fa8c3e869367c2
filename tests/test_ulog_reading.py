"""Reading logs through pyulog (``px4params.formats.ulog.parse``): a damaged log that sends
pyulog round in circles is refused in one line, by every command that reads logs, and real logs
are read well within the budget that catches it."""

from __future__ import annotations

import struct
import subprocess
import sys
from pathlib import Path

import pytest
from px4params.errors import ReadBudgetExceeded
from px4params.formats import ulog
from shared_data import SAMPLE_LOG, shared_file

# sample_log_small.ulg (pyulog's test log) cut to 60,000 bytes, with the size of the parameter
# message at byte 25,718 raised by 32 KiB (its high byte 0x80): pyulog 1.3.0 reads the claimed
# size, gets what is left, steps back by the claimed size and comes back to where it was.
CUT = 60_000
DAMAGED_AT = 25_718


def damaged_log(tmp_path: Path) -> Path:
    data = bytearray(shared_file(SAMPLE_LOG).read_bytes()[:CUT])
    pos = 16
    while pos < DAMAGED_AT:  # the messages' own framing leads to the damaged one
        pos += 3 + struct.unpack_from("<H", data, pos)[0]
    assert pos == DAMAGED_AT and data[pos + 2] == ord("P")
    data[pos + 1] |= 0x80
    path = tmp_path / "damaged.ulg"
    path.write_bytes(bytes(data))
    return path


@pytest.mark.parametrize(
    "command",
    [
        ["devid", "--log", "{log}"],
        ["migrate", "{log}", "-o", "{out}"],
        ["health", "{log}"],
    ],
    ids=["devid", "migrate", "health"],
)
def test_a_log_pyulog_goes_round_in_circles_on_is_refused(tmp_path: Path, command) -> None:
    # Each ran at 100% CPU until killed. A subprocess with a time limit: a guard that is gone
    # fails this test rather than hanging the suite.
    log, out = damaged_log(tmp_path), tmp_path / "out.params"
    argv = [part.format(log=log, out=out) for part in command]
    done = subprocess.run(
        [sys.executable, "-m", "px4params", *argv], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 1 and done.stdout == ""
    assert done.stderr == (
        f"px4params: error: {log}: not a readable ULog file (pyulog read more than 256 times its "
        f"{CUT} bytes without finishing: a damaged message sends it round in circles)\n"
    )
    assert not out.exists()


def test_the_budget_is_what_the_message_says_and_stops_reads_past_it(tmp_path: Path) -> None:
    log = tmp_path / "x.ulg"
    log.write_bytes(b"0123456789")
    with open(log, "rb") as file:
        budgeted = ulog._BudgetedFile(file, 4)
        assert budgeted.read(3) == b"012" and budgeted.read(1) == b"3"
        with pytest.raises(ReadBudgetExceeded):
            budgeted.read(1)
        budgeted.seek(0)  # seeking is free: a loop is caught by what it reads
        assert budgeted.tell() == 0
    assert ulog.READ_BUDGET == 256


@pytest.mark.parametrize(
    "name",
    [
        "sample_log_small.ulg",
        "sample_appended_multiple.ulg",
        "sample_px4_events.ulg",
        "frrs_ekf_failure.ulg",
    ],
)
def test_real_logs_are_read_about_once(name: str, monkeypatch) -> None:
    # pyulog read 1.0 to 1.11 times each log (the appended one: its appended data is read
    # again): the budget of 256 times leaves room for resyncing past damage.
    path = shared_file(name)
    read: list[int] = []

    class Counting(ulog._BudgetedFile):
        def read(self, size: int = -1) -> bytes:
            data = super().read(size)
            read.append(len(data))
            return data

    monkeypatch.setattr(ulog, "_BudgetedFile", Counting)
    log = ulog.parse(path, None)
    assert log.data_list and sum(read) < 1.2 * path.stat().st_size


def devid_log(path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "px4params", "devid", "--log", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_a_cut_log_warns_in_devid(tmp_path: Path) -> None:
    # The first 25,000 bytes of sample_log_small.ulg hold 87 of its 980 parameters: devid
    # listed the 6 ID parameters among them, of the log's 13, as if the log were whole.
    whole = shared_file(SAMPLE_LOG)
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(whole.read_bytes()[:25_000])
    done, was = devid_log(cut), devid_log(whole)
    assert done.returncode == 0 and done.stderr == (
        f"px4params: warning: {cut}: the log is cut short or damaged: device IDs logged after "
        "the break are missing\n"
    )
    listed = [line.split()[0] for line in done.stdout.splitlines()[:-1]]
    logged = [line.split()[0] for line in was.stdout.splitlines()[:-1]]
    assert len(listed) == 6 and len(logged) == 13 and set(listed) < set(logged)
    assert was.returncode == 0 and was.stderr == ""


def message_ends(data: bytes) -> list[int]:
    """Where each message of a whole log ends, by ULog's framing (a 16-byte file header, then
    messages of a 3-byte header, uint16 size and uint8 type, and that many bytes)."""
    ends, pos = [], 16
    while pos < len(data):
        pos += 3 + struct.unpack_from("<H", data, pos)[0]
        ends.append(pos)
    assert pos == len(data)
    return ends


def test_a_log_cut_inside_any_message_is_cut_and_one_cut_between_messages_is_not(
    tmp_path: Path,
) -> None:
    # pyulog took a file ending inside a data message for the log's end: migrate said
    # "log_cut": false of a log cut at 100 kB of 2 MB, and devid said nothing.
    data = shared_file(SAMPLE_LOG).read_bytes()
    ends = message_ends(data)
    assert not ulog.read_header(shared_file(SAMPLE_LOG)).corrupt
    path = tmp_path / "cut.ulg"
    # Inside a message's header (1 or 2 of its 3 bytes) or its body, early and late in the log.
    for end in (ends[200], ends[len(ends) // 2], ends[-2]):
        following = 3 + struct.unpack_from("<H", data, end)[0]
        for inside in {1, 2, 3, 4, following - 1} & set(range(1, following)):
            path.write_bytes(data[: end + inside])
            assert ulog.read_header(path).corrupt, (end, inside)
        # Between two messages nothing says more was to come: a log stopped there is whole.
        path.write_bytes(data[:end])
        assert not ulog.read_header(path).corrupt, end


def test_a_log_whose_tail_is_zeros_ends_where_they_start_cut(tmp_path: Path, monkeypatch) -> None:
    # A card that lost power leaves the preallocated rest of the file zero: pyulog stepped over
    # the zeros a byte at a time, re-reading each (21 s for 10 MB), and called the log whole.
    data = shared_file(SAMPLE_LOG).read_bytes()
    path = tmp_path / "zeros.ulg"
    path.write_bytes(data + bytes(4 << 20))
    read: list[int] = []

    class Counting(ulog._BudgetedFile):
        def read(self, size: int = -1) -> bytes:
            got = super().read(size)
            read.append(len(got))
            return got

    monkeypatch.setattr(ulog, "_BudgetedFile", Counting)
    header = ulog.read_header(path)
    assert header.corrupt
    assert sum(read) < 1.2 * len(data)  # the zeros are looked over once, outside reads
    assert header.parameters == ulog.read_header(shared_file(SAMPLE_LOG)).parameters
    # Zeros with data after them are no end: pyulog's own resync reads past them.
    ends = message_ends(data)
    middle = ends[len(ends) // 2]
    path.write_bytes(data[:middle] + bytes(64) + data[middle:])
    assert ulog.read_header(path).corrupt
    assert ulog.read_header(path).parameters == header.parameters
