"""``px4params gui``: the device manifest in a browser, over a vehicle on MAVLink or a store file
(the page and its server are ``px4params.gui``)."""

from __future__ import annotations

import socket
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from px4params.cli.commands.mavlink import parse_udp
from px4params.cli.options import store_options
from px4params.cli.parsing import RawDescriptionHelpFormatter
from px4params.errors import CommandError
from px4params.status import EXIT_OK

if TYPE_CHECKING:
    import argparse

_DESCRIPTION = """\
Serve a ground-station page for the device manifest on loopback and print its
URL. With --udp it talks MAVLink to a vehicle (px4params mavlink serve, or a
PX4): it fetches the parameter metadata over MAVLink FTP (COMPONENT_METADATA),
else from --metadata FILE. With --store it edits a store file offline, with the
same checks, saving each accepted write atomically.

The page shows each structured parameter's instances as forms built from the
metadata (union variants, units, ranges, enums, switches, arrays), the classic
parameters by group with search, modified marks and reset, and device health.
Edits collect into a review; nothing is written until you confirm it, and each
write is read back and marked acknowledged or refused with the vehicle's reason.
Instances are added and removed through the parameter's instance mask
(INA238_INST), a plain parameter write."""


def cmd_gui(args: argparse.Namespace) -> int:
    import uvicorn

    from px4params.gui.app import make_app
    from px4params.gui.vehicle import MavlinkVehicle, StoreVehicle

    host, port = args.http
    if args.udp is not None and args.store is not None:
        args.gui_parser.error("--udp (a vehicle) and --store (a file) do not go together")
    if args.udp is not None:
        vehicle: Any = MavlinkVehicle(args.udp, args.metadata)
    else:
        vehicle = StoreVehicle(args.store, args.classic, args.dsdl or [])
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as e:
        sock.close()
        vehicle.close()
        raise CommandError(f"cannot listen on http {host}:{port}: {e.strerror or e}") from None
    config = uvicorn.Config(make_app(vehicle), log_level="warning", lifespan="off")
    server = uvicorn.Server(config)
    sock.listen(128)  # connections wait in the backlog until the server accepts them
    bound = sock.getsockname()
    url = f"http://{bound[0]}:{bound[1]}/"
    print(f"px4params gui on {url} ({vehicle.mode}: {vehicle.source}); Ctrl-C stops", flush=True)
    if args.open:
        import webbrowser

        webbrowser.open(url)
    try:
        server.run(sockets=[sock])
    finally:
        vehicle.close()
    return EXIT_OK


def _http(text: str) -> tuple[str, int]:
    return parse_udp(text)


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers ``px4params gui``."""
    p = sub.add_parser(
        name,
        help=summary,
        description=_DESCRIPTION,
        epilog="""\
examples:
  px4params gui --udp 127.0.0.1:14540                 # a vehicle (px4params mavlink serve)
  px4params gui --store vehicle.store --http 127.0.0.1:8081 --open""",
        formatter_class=RawDescriptionHelpFormatter,
    )
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "--udp", type=parse_udp, metavar="HOST:PORT", help="the vehicle's MAVLink UDP address"
    )
    store_options(p)
    p.add_argument(
        "--http",
        type=_http,
        default=("127.0.0.1", 8080),
        metavar="HOST:PORT",
        help="where the page is served (default 127.0.0.1:8080; port 0 picks a free one)",
    )
    p.add_argument(
        "--metadata",
        metavar="FILE",
        help="parameters.json for a vehicle that does not serve its metadata over MAVLink",
    )
    p.add_argument("--open", action="store_true", help="open the page in the default browser")
    p.set_defaults(func=cmd_gui, gui_parser=p)
