"""``px4params gui``: the device manifest in a browser, over a vehicle on MAVLink or a store file
(the page and its server are ``px4params.gui``)."""

from __future__ import annotations

import ipaddress
import socket
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from px4params.cli.commands.mavlink import add_signing_option, parse_udp, signing_key
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
(INA238_INST), a plain parameter write.

Only who holds the printed URL gets in: it carries a secret token for this
run (the first visit turns it into a cookie), and the server answers only to
the loopback names and the address it listens on (--allow-host adds names).
Listening on anything but loopback needs --allow-remote; see docs/security.md."""


#: Bytes a WebSocket message from the client may have (the page sends none).
WS_MAX_MESSAGE = 4096


def cmd_gui(args: argparse.Namespace) -> int:
    import uvicorn

    from px4params.gui.admission import allowed_hosts, new_token
    from px4params.gui.app import make_app
    from px4params.gui.connections import RequestDeadline
    from px4params.gui.vehicle import MavlinkVehicle, StoreVehicle

    host, port = args.http
    if args.udp is not None and args.store is not None:
        args.gui_parser.error("--udp (a vehicle) and --store (a file) do not go together")
    remote = not _is_loopback(host)
    if remote and not args.allow_remote:
        raise CommandError(
            f"--http {host}:{port} is not a loopback address: other machines could change the "
            "vehicle's parameters; add --allow-remote to mean it (docs/security.md)"
        )
    if args.signing_key is not None and args.udp is None:
        args.gui_parser.error("--signing-key signs a vehicle's link: it needs --udp")
    if args.udp is not None:
        key = signing_key(args.signing_key)
        vehicle: Any = MavlinkVehicle(args.udp, args.metadata, signing_key=key)
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
    bound_host, bound_port = sock.getsockname()[:2]
    token = new_token()
    hosts = allowed_hosts(bound_port, bound_host, args.allow_host or ())
    app = make_app(vehicle, token=token, hosts=hosts, cookie=f"px4params-gui-{bound_port}")
    # Open WebSockets are closed at shutdown and their handlers end; the bound makes sure a
    # stuck one cannot keep SIGTERM or Ctrl-C from stopping the server.
    # The page sends nothing over its WebSocket: a client's messages are capped as small.
    config = uvicorn.Config(
        app,
        http=RequestDeadline,  # a request not whole within 10 s closes its connection
        log_level="warning",
        lifespan="off",
        # uvicorn annotates int but hands it to asyncio.wait_for, which takes seconds as float
        timeout_graceful_shutdown=0.5,  # type: ignore[arg-type]
        ws_max_size=WS_MAX_MESSAGE,
    )
    server = uvicorn.Server(config)
    sock.listen(128)  # connections wait in the backlog until the server accepts them
    shown = bound_host if bound_host != "0.0.0.0" else "127.0.0.1"
    url = f"http://{shown}:{bound_port}/?token={token}"
    if remote:
        names = ", ".join(sorted(hosts))
        print(
            f"px4params gui: warning: listening on {bound_host}:{bound_port}, reachable from "
            f"other machines over plain HTTP: whoever has the URL below can change the "
            f"vehicle's parameters (host names answered: {names})",
            file=sys.stderr,
            flush=True,
        )
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


def _is_loopback(host: str) -> bool:
    """Whether ``host`` (an address or a name) is this machine's loopback only."""
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        pass
    try:
        found = socket.getaddrinfo(host, None, socket.AF_INET, socket.SOCK_STREAM)
    except OSError:
        return False  # the bind will say why
    return bool(found) and all(ipaddress.ip_address(f[4][0]).is_loopback for f in found)


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers ``px4params gui``."""
    p = sub.add_parser(
        name,
        help=summary,
        description=_DESCRIPTION,
        epilog="""\
examples:
  px4params gui --udp 127.0.0.1:14540                 # a vehicle (px4params mavlink serve)
  px4params gui --store vehicle.store --http 127.0.0.1:8081 --open
  px4params gui --store vehicle.store --http 192.168.1.5:8080 --allow-remote  # docs/security.md""",
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
    add_signing_option(p, "the messages to the vehicle (with --udp)")
    p.add_argument(
        "--metadata",
        metavar="FILE",
        help="parameters.json for a vehicle that does not serve its metadata over MAVLink",
    )
    p.add_argument(
        "--allow-host",
        action="append",
        metavar="NAME",
        help="also answer to this host name (NAME or NAME:PORT; repeatable), e.g. the name "
        "other machines use with --allow-remote",
    )
    p.add_argument(
        "--allow-remote",
        action="store_true",
        help="allow --http on an address other machines can reach (plain HTTP; the token "
        "URL is still needed)",
    )
    p.add_argument("--open", action="store_true", help="open the page in the default browser")
    p.set_defaults(func=cmd_gui, gui_parser=p)
