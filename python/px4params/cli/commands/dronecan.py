"""``px4params dronecan``: the store's parameters as a DroneCAN node behind an SLCAN line
(``serve``), and a remote node's parameters from here (``param``)."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING, Any

from px4params.cli.options import bench_options, identifier, seconds, store_options
from px4params.cli.parsing import RawDescriptionHelpFormatter
from px4params.status import EXIT_OK
from px4params.store.store import default_store_path

if TYPE_CHECKING:
    import argparse

__all__ = ["add_parser"]

_BITRATES = ("10000", "20000", "50000", "100000", "125000", "250000", "500000", "800000", "1000000")


_node_id = identifier("DroneCAN node ID", 127)


def cmd_serve(args: argparse.Namespace) -> int:
    from px4params.links.dronecan_node import NODE_NAME, DronecanParamNode
    from px4params.links.slcan import SerialPort, open_pty, open_serial
    from px4params.store.session import open_session
    from px4params.vehicle.health import ManifestHealth, worst

    existed = os.path.exists(args.store or default_store_path())
    session = open_session(args.store, args.classic, args.dsdl or ())
    store, path = session.store, session.path
    monitor = ManifestHealth(store, args.bench, duration=args.bench_duration)

    def health() -> tuple[str, int]:
        devices = monitor.devices()
        return worst(devices), sum(d.health != "nominal" for d in devices)

    def log(line: str) -> None:
        print(line, flush=True)

    port: SerialPort
    if args.slcan_pty:
        port, device = open_pty()
        log(f"slcan: {device}")  # first line: a client opens this
    else:
        port, device = open_serial(args.slcan), args.slcan
    node = DronecanParamNode(
        store, port, node_id=args.node_id, session=session, health=health, log=log
    )
    node.adapter.bitrate = int(args.bitrate)
    where = path if existed else f"{path}, new: written on SAVE"
    log(
        f"serving {len(node.params)} parameters as DroneCAN node {args.node_id} "
        f"(name {NODE_NAME}) behind an SLCAN adapter on {device} "
        f"(store: {where}); Ctrl-C stops"
    )
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, lambda *_: node.stop())
    with contextlib.suppress(KeyboardInterrupt):
        node.serve_forever()
    s = node.stats
    log(
        f"stopped: {s['requests']} requests ({s['ignored']} ignored), {s['accepted']} writes "
        f"accepted, {s['refused']} refused, {s['saves']} saves"
        + (f", {s['dropped']} writes to a host that did not read dropped" if s["dropped"] else "")
    )
    return EXIT_OK


@contextlib.contextmanager
def _client(args: argparse.Namespace) -> Iterator[Any]:
    """The client on an opened SLCAN channel, closed again (``C``) when the command ends."""
    from px4params.links.dronecan_client import DronecanParamClient
    from px4params.links.slcan import SlcanHost, open_serial

    host = SlcanHost(open_serial(args.slcan))
    host.start(int(args.bitrate))
    try:
        yield DronecanParamClient(host, args.node, local_node=args.local_node, timeout=args.timeout)
    finally:
        host.stop()


def _line(param: Any) -> str:
    from px4params.links.dronecan_client import shown

    extra = []
    if "empty" not in param.default:
        extra.append(f"default {shown(param.default)}")
    if "empty" not in param.min or "empty" not in param.max:
        extra.append(f"{shown(param.min)} .. {shown(param.max)}")
    tail = f"  ({', '.join(extra)})" if extra else ""
    return f"{param.name} = {shown(param.value)}{tail}"


def cmd_param_list(args: argparse.Namespace) -> int:
    terminal = sys.stderr.isatty()

    def progress(count: int) -> None:
        if terminal and count % 25 == 0:
            print(f"\r{count} parameters read...", end="", file=sys.stderr, flush=True)

    with _client(args) as client:
        rows = [_line(p) for p in client.list(progress)]
    if terminal:
        print("\r" + " " * 40 + "\r", end="", file=sys.stderr)
    print("\n".join(rows))
    print(f"{len(rows)} parameters on node {args.node}")
    return EXIT_OK


def cmd_param_get(args: argparse.Namespace) -> int:
    from px4params.links.dronecan_client import DronecanError

    with _client(args) as client:
        param = client.get(args.name)
    if param is None:
        raise DronecanError(f"node {args.node} has no parameter {args.name}")
    print(_line(param))
    return EXIT_OK


def cmd_param_set(args: argparse.Namespace) -> int:
    from px4params.links.dronecan_client import DronecanError, parse_value

    with _client(args) as client:
        before = client.get(args.name)
        if before is None:
            raise DronecanError(f"node {args.node} has no parameter {args.name}")
        try:
            value = parse_value(args.value, before.value)
        except DronecanError as e:
            raise DronecanError(f"{args.name}: {e}") from None
        print(_line(client.set(args.name, value)))
    return EXIT_OK


def cmd_param_save(args: argparse.Namespace) -> int:
    with _client(args) as client:
        client.save()
    print(f"node {args.node} saved its parameters")
    return EXIT_OK


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers ``px4params dronecan``."""
    p = sub.add_parser(name, help=summary, description="DroneCAN parameters over SLCAN.")
    verbs = p.add_subparsers(dest="dronecan_command", required=True, metavar="VERB")
    s = verbs.add_parser(
        "serve",
        help="serve the store's parameters as a DroneCAN node behind an SLCAN line",
        formatter_class=RawDescriptionHelpFormatter,
        description="""\
Be a DroneCAN node that serves the store's parameters, behind an SLCAN
adapter on a serial line (as a flight controller passing CAN over USB
is): the host opens the channel (O, S8, ...) and DroneCAN tools (the
DroneCAN GUI tool, pydronecan) talk to the node through it.

The node sends NodeStatus every second (health from the manifest, or
from the simulated bench with --bench) and answers GetNodeInfo (name
org.px4params), param.GetSet by index and by name, param.ExecuteOpcode
(SAVE writes the store file; ERASE writes one with every value at its
default, used after a restart) and RestartNode. Parameters are the
classic ones, every leaf of every instance under its long name
(INA238#1.bus.i2c.address is INA238_1_I2C_ADDRESS) and the instance
masks (INA238_INST). Ctrl-C or SIGTERM stops.""",
        epilog="""\
examples:
  px4params dronecan serve --slcan-pty --store vehicle.store   # prints slcan: /dev/pts/N
  px4params dronecan serve --slcan /dev/ttyACM0 --node-id 10
  dronecan_gui_tool   # then open /dev/pts/N as the CAN interface""",
    )
    line = s.add_mutually_exclusive_group(required=True)
    line.add_argument("--slcan", metavar="DEVICE", help="serial device to serve on")
    line.add_argument(
        "--slcan-pty",
        action="store_true",
        help="make a pseudo-terminal and print 'slcan: /dev/pts/N' as the first line",
    )
    s.add_argument(
        "--node-id",
        type=_node_id,
        default=1,
        metavar="N",
        help="this node's ID, 1..127 (default 1, as PX4's UAVCAN_NODE_ID)",
    )
    s.add_argument(
        "--bitrate",
        choices=_BITRATES,
        default="1000000",
        metavar="B",
        help="CAN bit rate the adapter starts with (the host may set another; default 1000000)",
    )
    store_options(s)
    bench_options(s, "the devices' health in NodeStatus")
    s.set_defaults(func=cmd_serve)

    q = verbs.add_parser(
        "param",
        help="list, get, set or save a remote node's parameters",
        formatter_class=RawDescriptionHelpFormatter,
        description="""\
Read and write the parameters of a DroneCAN node (a peripheral: GPS,
power module, ESC; or 'px4params dronecan serve') through an SLCAN
adapter, with param.GetSet and param.ExecuteOpcode. A set takes the
parameter's own kind of value (integer, real or boolean); the node
checks it and a refused write fails with the value it kept. 'save'
makes the node write its parameters to non-volatile storage.""",
        epilog="""\
examples:
  px4params dronecan param list --slcan /dev/ttyACM0 --node 10
  px4params dronecan param get --slcan /dev/ttyACM0 --node 10 INA238_1_I2C_ADDRESS
  px4params dronecan param set --slcan /dev/ttyACM0 --node 10 INA238_1_I2C_ADDRESS 0x44
  px4params dronecan param save --slcan /dev/ttyACM0 --node 10""",
    )
    actions = q.add_subparsers(dest="dronecan_param_command", required=True, metavar="ACTION")
    for action, about, func in (
        ("list", "every parameter, by index", cmd_param_list),
        ("get", "one parameter by name", cmd_param_get),
        ("set", "write one parameter by name", cmd_param_set),
        ("save", "ExecuteOpcode SAVE", cmd_param_save),
    ):
        a = actions.add_parser(action, help=about, description=f"{about.capitalize()}.")
        a.add_argument("--slcan", metavar="DEVICE", required=True, help="the SLCAN adapter")
        a.add_argument("--node", type=_node_id, required=True, metavar="N", help="the remote node")
        a.add_argument(
            "--local-node",
            type=_node_id,
            default=127,
            metavar="N",
            help="this program's node ID (default 127, as the DroneCAN GUI tool)",
        )
        a.add_argument(
            "--bitrate", choices=_BITRATES, default="1000000", metavar="B", help="CAN bit rate"
        )
        a.add_argument(
            "--timeout",
            type=seconds(3600.0),
            default=1.0,
            metavar="S",
            help="seconds to wait for each response (default 1; retried twice)",
        )
        if action in ("get", "set"):
            a.add_argument("name", metavar="NAME")
        if action == "set":
            a.add_argument("value", metavar="VALUE")
        a.set_defaults(func=func)
