"""``px4params mavlink serve``: the store's parameters over MAVLink (``links.mavlink``)."""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from px4params.cli.options import bench_options, identifier, store_options
from px4params.cli.parsing import RawDescriptionHelpFormatter, type_error
from px4params.errors import CommandError
from px4params.status import EXIT_OK
from px4params.store.store import default_store_path

if TYPE_CHECKING:
    import argparse

__all__ = ["add_parser", "add_signing_option", "parse_udp", "signing_key"]


def parse_udp(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (argparse type): a host name or IPv4 address and a port 0..65535."""
    host, sep, port = text.strip().rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise type_error(
            f"'{text}' is not HOST:PORT (expected e.g. 127.0.0.1:14550, port 0..65535)"
        )
    return host, int(port)


_id = identifier("MAVLink ID", 255)


def _bench_health(args: argparse.Namespace, store: Any) -> Callable[[], list[str]]:
    """Health lines of the store's manifest booted on the simulated bench ``--bench``: one per
    configured instance, as the commander reports them; booted again when the manifest
    changes."""
    from px4params.vehicle.health import ManifestHealth

    health = ManifestHealth(store, args.bench, duration=args.bench_duration)
    return lambda: [f"health: {d.line}" for d in health.devices()]


def cmd_serve(args: argparse.Namespace) -> int:
    from px4params.links.mavlink import MavlinkParamServer
    from px4params.store.flat import flat_map
    from px4params.store.session import open_session

    key = signing_key(args.signing_key)

    # The same store, classic parameters and types as `px4params param` uses.
    existed = os.path.exists(args.store or default_store_path())
    session = open_session(args.store, args.classic, args.dsdl or ())
    store, path = session.store, session.path
    where = path if existed else f"{path}, new: written on the first accepted change"
    flat_count = len(flat_map(store).table())  # also refuses types that cannot be destructured

    def classic_int(name: str, fallback: int) -> int:
        if name in store.parameters and store.classic(name) is not None:
            value = store.get(name)
            return int(value) if 1 <= value <= 255 else fallback
        return fallback

    system_id = args.sysid or classic_int("MAV_SYS_ID", 1)
    component_id = args.compid or classic_int("MAV_COMP_ID", 1)

    def log(line: str) -> None:
        print(line, flush=True)

    health = _bench_health(args, store) if args.bench else None
    host, port = args.udp
    try:
        server = MavlinkParamServer(
            store,
            host,
            port,
            session=session,
            system_id=system_id,
            component_id=component_id,
            gcs=args.gcs or (),
            log=log,
            health=health,
            signing_key=key,
        )
    except OSError as e:
        raise CommandError(f"cannot listen on udp {host}:{port}: {e.strerror or e}") from None
    bound_host, bound_port = server.address
    total = len(server.entries())
    if key is None:
        signed = "unsigned: anyone who can send to it can set parameters (--signing-key FILE)"
    else:
        signed = f"signed with the key in {args.signing_key} (unsigned messages are dropped)"
    log(
        f"serving {total} parameters ({total - flat_count} classic, {flat_count} destructured) "
        f"on udp {bound_host}:{bound_port} as system {system_id}, component {component_id}, "
        f"{signed} (store: {where}); Ctrl-C stops"
    )
    files = server.metadata
    log(
        f"component metadata: {files.general_uri} (crc {files.general_crc:#010x}) lists "
        f"parameters.json.xz ({len(files.parameters)} bytes), over MAVLink FTP"
    )
    if threading.current_thread() is threading.main_thread():
        # `kill` (SIGTERM) stops as cleanly as Ctrl-C.
        signal.signal(signal.SIGTERM, lambda *_: server.stop())
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        server.stop()
    s = server.stats
    dropped = ""
    if key is not None:
        dropped = (
            f"; dropped {s['unsigned']} unsigned and {s['badly_signed']} wrongly signed "
            f"messages ({s['param_set_dropped']} PARAM_SET)"
        )
    log(
        f"stopped: {s['received']} messages received ({s['ignored']} ignored), "
        f"{s['accepted']} writes accepted, {s['refused']} refused{dropped}"
    )
    return EXIT_OK


def signing_key(path: str | None) -> bytes | None:
    """The key in ``--signing-key FILE`` (None without the option); a bad file is a one-line
    error."""
    if path is None:
        return None
    from px4params.links.mavlink_signing import load_key

    key = load_key(path)
    if os.stat(path).st_mode & 0o077:  # as ssh says of a private key others can read
        print(
            f"px4params: warning: {path} can be read by other users: chmod 600 {path}",
            file=sys.stderr,
            flush=True,
        )
    return key


def add_signing_option(p: Any, who: str) -> None:
    """``--signing-key FILE`` (``mavlink serve`` and the page's ``--udp``)."""
    p.add_argument(
        "--signing-key",
        metavar="FILE",
        help=f"sign {who} with MAVLink 2 signing and drop unsigned or wrongly signed messages; "
        "FILE holds the 32-byte key: raw, as 64 hex digits (the SHA-256 of the passphrase "
        "MAVProxy's 'signing setup' or QGC takes) or PX4's mavlink-signing-key.bin",
    )


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers ``px4params mavlink``."""
    p = sub.add_parser(
        name,
        help=summary,
        description="MAVLink parameter protocol for ground stations.",
    )
    verbs = p.add_subparsers(dest="mavlink_command", required=True, metavar="VERB")
    s = verbs.add_parser(
        "serve",
        help="serve classic and destructured parameters over UDP",
        formatter_class=RawDescriptionHelpFormatter,
        description="""\
Serve the store's parameters with the MAVLink parameter protocol, as PX4
does: the classic parameters and every leaf of every structured instance
as a flat parameter (INA238#1.bus.i2c.address is INA238_1C; see
'px4params param flat'). Answers PARAM_REQUEST_LIST (_HASH_CHECK first),
PARAM_REQUEST_READ (by name or index) and PARAM_SET (type and range
checked; accepted writes are saved to the store file at once), sends
HEARTBEAT and, when asked, AUTOPILOT_VERSION (int32 values are encoded
bytewise). Anything else is ignored. Ctrl-C or SIGTERM stops.

Anyone who can send to the address can set parameters unless the link is
signed (--signing-key FILE, MAVLink 2 signing as PX4 does it); listen on
loopback unless the vehicle's link needs more (see docs/security.md).""",
        epilog="""\
examples:
  px4params mavlink serve --udp 127.0.0.1:14540 --store vehicle.store
  px4params mavlink serve --udp 127.0.0.1:14540 --signing-key link.key   # MAVLink 2 signing
  px4params mavlink serve --udp 127.0.0.1:14580 --gcs 127.0.0.1:14550   # QGC finds it
  mavproxy.py --master udpout:127.0.0.1:14540   # then: param show INA238_*""",
    )
    s.add_argument(
        "--udp",
        type=parse_udp,
        required=True,
        metavar="HOST:PORT",
        help="address to listen on (port 0: any free port, printed at start)",
    )
    s.add_argument(
        "--gcs",
        type=parse_udp,
        action="append",
        metavar="HOST:PORT",
        help="also send heartbeats here before it speaks, e.g. QGC's 127.0.0.1:14550 (repeatable)",
    )
    s.add_argument("--sysid", type=_id, metavar="N", help="system ID (default: MAV_SYS_ID, else 1)")
    s.add_argument(
        "--compid", type=_id, metavar="N", help="component ID (default: MAV_COMP_ID, else 1)"
    )
    add_signing_option(s, "every message sent")
    store_options(s)  # --store, --classic, --dsdl as for `px4params param`
    bench_options(
        s,
        "each device's health as STATUSTEXT every 2 s ('health: ina238 INA238#1 on I2C bus 2 "
        "address 0x45: critical: ...')",
    )
    s.set_defaults(func=cmd_serve)
