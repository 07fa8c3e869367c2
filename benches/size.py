"""Code size of the core as firmware links it: ``.text`` bytes of a ``no_std`` probe that
exports only what it names, built from this workspace with ``opt-level = "z"`` (``--opt-level
s`` for the other size level), fat LTO, ``codegen-units = 1`` and ``panic = "abort"``, per
feature set, each with the core as hosts build it and with its ``compact`` feature (firmware:
every value through one small walk; the same bytes):

- ``codec``: encode and decode from and to a flat leaf list (``encode_leaves`` /
  ``decode_leaves``);
- ``core``: that, plus leaf get/set in encoded data, descattering, CAN frames and receive, and
  the store over static tables (open, add, remove, get and set values and leaves, the next
  instance): issue 17's "everything";
- ``all``: that, plus the whole C ABI of ``crates/px4params-ffi``, whose load and save bring
  the store file format and the translation of older type versions.

Ceilings, for the ``compact`` build, are the sizes reached (rounded up to 32 bytes), lowered
as the code shrinks; the exit status is 1 when a probe is over its ceiling. Issue 17 set codec
<= 6 KB and core <= 16 KB (x86_64); issue 39 aims at codec <= 4 KiB and core <= 10 KiB on
Cortex-M7. See docs/firmware.md#size for the figures.

    python benches/size.py [--target TRIPLE] [--cpu CPU] [--opt-level s|z] [--keep DIR]
                           [--symbols N]

``--target thumbv7em-none-eabihf`` (``--cpu cortex-m7``, as PX4's FMUv5x/v6x fly, or
``cortex-m4``, Cortex-M4F, measured without ceilings) builds each probe as a static library
and links it with ``arm-none-eabi-gcc``, keeping only what the exports reach
(``--gc-sections``), against newlib-nano for the memory routines (``memcpy``, ``memset``,
``memcmp``), as a firmware links its libc's, then reads the ``.text`` of that image; it needs
``rustup target add thumbv7em-none-eabihf`` and Debian's ``gcc-arm-none-eabi``. It also
measures the C baseline the same way where ``../shared/anchors/dronecan-c`` is (libcanard's
whole API, and with the four messages' dsdlc code; gcc -Os, which gcc 12's -Oz equals here).

``--symbols N`` lists each probe's N largest functions (``nm --size-sort``).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# Ceilings of the compact build's .text, by target triple (None: the host).
TARGETS: dict[str | None, dict[str, int | None]] = {
    None: {"codec": 5216, "core": 13088, "all": None},
    # Issue 39's targets: codec 4 KiB, core (codec, leaves, descattering, frames, store) 10 KiB.
    "thumbv7em-none-eabihf": {"codec": 4096, "core": 10240, "all": None},
}

PROBE_TOML = """\
[package]
name = "px4params-size-probe"
version = "0.0.0"
edition = "2021"
publish = false

[lib]
crate-type = ["{crate_type}"]
path = "lib.rs"

[features]
core = []
all = ["core", "dep:px4params-ffi"]
compact = ["px4params-core/compact"]

[dependencies]
px4params-core = {{ path = "{core}" }}
px4params-ffi = {{ path = "{ffi}", features = ["firmware"], optional = true }}

[profile.release]
opt-level = "{opt_level}"
lto = "fat"
codegen-units = 1
panic = "abort"

[workspace]
"""

# Every export takes its arguments from the caller, so that nothing is constant-folded away.
PROBE_RS = """\
#![no_std]
// The exports pass Rust types: the probe is linked for its size, never called from C.
#![allow(improper_ctypes_definitions)]
use px4params_core::codec::{decode_leaves, encode_leaves, DecodeOptions, EncodeOptions};
use px4params_core::layout::Layout;
use px4params_core::Scalar;

#[cfg(not(feature = "all"))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {}
}

#[no_mangle]
pub extern "C" fn probe_encode(
    layout: &Layout<'static>, root: u32, leaves: *const Scalar, n: usize, out: *mut u8,
    cap: usize, tao: bool,
) -> isize {
    let leaves = unsafe { core::slice::from_raw_parts(leaves, n) };
    let out = unsafe { core::slice::from_raw_parts_mut(out, cap) };
    let options = EncodeOptions { tao, saturate: false, keep_versions: false };
    match encode_leaves(layout, root, leaves, out, options) {
        Ok(n) => n as isize,
        Err(_) => -1,
    }
}

#[no_mangle]
pub extern "C" fn probe_decode(
    layout: &Layout<'static>, root: u32, data: *const u8, len: usize, leaves: *mut Scalar,
    n: usize, tao: bool,
) -> isize {
    let data = unsafe { core::slice::from_raw_parts(data, len) };
    let leaves = unsafe { core::slice::from_raw_parts_mut(leaves, n) };
    match decode_leaves(layout, root, data, leaves, DecodeOptions { tao, allow_trailing: false }) {
        Ok(decoded) => decoded.bits as isize,
        Err(_) => -1,
    }
}

#[cfg(feature = "all")]
pub use px4params_ffi::*;

#[cfg(feature = "core")]
mod more {
    use super::*;
    use px4params_core::leaf::{get_leaf_at, set_leaf_at};
    use px4params_core::store::{ParamDef, Slot, Store, Which};
    use px4params_core::scatter::Scattered;
    use px4params_core::transfer::{frames, receive};

    #[no_mangle]
    pub extern "C" fn probe_get_leaf(
        layout: &Layout<'static>, root: u32, data: *const u8, len: usize, k: usize,
        out: &mut Scalar,
    ) -> isize {
        let data = unsafe { core::slice::from_raw_parts(data, len) };
        match get_leaf_at(layout, root, data, k, false) {
            Ok((_, v)) => { *out = v; 0 }
            Err(_) => -1,
        }
    }

    #[no_mangle]
    pub extern "C" fn probe_set_leaf(
        layout: &Layout<'static>, root: u32, data: *const u8, len: usize, k: usize, v: Scalar,
        out: *mut u8, cap: usize,
    ) -> isize {
        let data = unsafe { core::slice::from_raw_parts(data, len) };
        let out = unsafe { core::slice::from_raw_parts_mut(out, cap) };
        let options = EncodeOptions { tao: false, saturate: false, keep_versions: false };
        match set_leaf_at(layout, root, data, k, v, out, options) {
            Ok(n) => n as isize,
            Err(_) => -1,
        }
    }

    #[no_mangle]
    pub extern "C" fn probe_frames(
        payload: *const u8, len: usize, seed: u16, out: *mut u8,
    ) -> usize {
        let payload = unsafe { core::slice::from_raw_parts(payload, len) };
        let mut written = 0;
        for frame in frames(payload, seed, 0, false) {
            let bytes = frame.as_bytes();
            let to = unsafe { out.add(written) };
            unsafe { core::ptr::copy_nonoverlapping(bytes.as_ptr(), to, bytes.len()) };
            written += bytes.len();
        }
        written
    }

    /// A transfer's frames checked and decoded where they lie (descattering).
    #[no_mangle]
    pub extern "C" fn probe_receive_decode(
        layout: &Layout<'static>, root: u32, frames_in: *const &[u8], n: usize, seed: u16,
        leaves: *mut Scalar, cap: usize,
    ) -> isize {
        let frames_in = unsafe { core::slice::from_raw_parts(frames_in, n) };
        let leaves = unsafe { core::slice::from_raw_parts_mut(leaves, cap) };
        let Ok(received) = receive(frames_in, seed) else { return -1 };
        let stream = Scattered::new(&received.payload);
        let options = DecodeOptions { tao: true, allow_trailing: false };
        match decode_leaves(layout, root, &stream, leaves, options) {
            Ok(decoded) => decoded.bits as isize,
            Err(_) => -1,
        }
    }

    // The store over static tables and memory, as the C ABI keeps it.
    type S = Store<&'static [ParamDef], &'static mut [Slot], &'static mut [u8]>;

    fn which(default: u8) -> Which {
        if default == 0 { Which::Value } else { Which::Default }
    }

    #[no_mangle]
    pub extern "C" fn probe_store_open(
        layout: &Layout<'static>, defs: &'static [ParamDef], slots: &'static mut [Slot],
        bytes: &'static mut [u8], defaults: &[&[u8]], out: &mut core::mem::MaybeUninit<S>,
    ) -> isize {
        let Ok(mut store) = S::new(layout, defs, slots, bytes) else { return -1 };
        for (param, default) in defaults.iter().enumerate() {
            if store.set_type_default(layout, param as u32, default).is_err() {
                return -1;
            }
        }
        store.mark_saved();
        out.write(store);
        0
    }

    #[no_mangle]
    pub extern "C" fn probe_store_add(store: &mut S, param: u32, instance: i32) -> isize {
        let wanted = u16::try_from(instance).ok();
        store.add(param, wanted).map_or(-1, |i| i as isize)
    }

    #[no_mangle]
    pub extern "C" fn probe_store_remove(store: &mut S, param: u32, instance: u16) -> isize {
        store.remove(param, instance).map_or(-1, |()| 0)
    }

    #[no_mangle]
    pub extern "C" fn probe_store_get(
        store: &S, param: u32, instance: u16, default: u8, out: &mut [u8],
    ) -> isize {
        match store.get(param, instance, which(default)) {
            Ok(v) if v.len() <= out.len() => { out[..v.len()].copy_from_slice(v); v.len() as isize }
            _ => -1,
        }
    }

    #[no_mangle]
    pub extern "C" fn probe_store_set(
        store: &mut S, layout: &Layout<'static>, param: u32, instance: u16, default: u8,
        data: &[u8],
    ) -> isize {
        store.set_encoded(layout, param, instance, which(default), data).map_or(-1, |()| 0)
    }

    #[no_mangle]
    pub extern "C" fn probe_store_read(
        store: &S, layout: &Layout<'static>, param: u32, instance: u16, default: u8, k: usize,
        out: &mut Scalar,
    ) -> isize {
        match store.read(layout, param, instance, which(default), k) {
            Ok(v) => { *out = v; 0 }
            Err(_) => -1,
        }
    }

    #[no_mangle]
    pub extern "C" fn probe_store_set_leaf(
        store: &mut S, layout: &Layout<'static>, param: u32, instance: u16, default: u8,
        k: usize, v: Scalar, saturate: bool,
    ) -> isize {
        let w = which(default);
        store.set_leaf_at(layout, param, instance, w, k, v, saturate).map_or(-1, |()| 0)
    }

    #[no_mangle]
    pub extern "C" fn probe_store_next(store: &S, param: u32, after: i32) -> isize {
        match store.instances(param) {
            Ok(mut present) => present.find(|&i| i32::from(i) > after).map_or(-2, |i| i as isize),
            Err(_) => -1,
        }
    }
}
"""


def binutil(tool: str, library: Path) -> str:
    """The binutils program that reads `library` (the ARM one for a Cortex-M image)."""
    return f"arm-none-eabi-{tool}" if library.suffix == ".elf" else tool


def text_size(library: Path) -> int:
    command = [binutil("size", library), "-A", str(library)]
    out = subprocess.run(command, capture_output=True, text=True, check=True)
    match = re.search(r"^\.text\s+(\d+)", out.stdout, re.M)
    assert match, out.stdout
    return int(match.group(1))


def largest(library: Path, n: int) -> list[str]:
    out = subprocess.run(
        [binutil("nm", library), "--size-sort", "-r", "-C", "--radix=d", str(library)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    # Weak definitions too (" W "): compiler_builtins' routines, such as the 64-bit shifts
    # and conversions a 32-bit core calls, are weak.
    code = (" t ", " T ", " W ")
    return [line for line in out.splitlines() if any(kind in line for kind in code)][:n]


# How a Cortex-M7 image is linked: the exports are the roots, everything else is collected.
# gcc's flags per core: PX4's FMUv5x/v6x fly a Cortex-M7 (double-precision FPU), older boards
# a Cortex-M4F (single precision).
ARM_FLAGS = {
    "cortex-m7": ["-mcpu=cortex-m7", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv5-d16"],
    "cortex-m4": ["-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv4-sp-d16"],
}
EXPORTS = re.findall(r'pub extern "C" fn (\w+)', PROBE_RS)
# newlib-nano, the C library arm-none-eabi-gcc links with its nano specs.
LIBC = "-lc_nano"
MEMORY_ROUTINES = {"memcpy", "memmove", "memset", "memcmp", "bcmp"} | {
    f"__aeabi_{name}{align}"
    for name in ("memcpy", "memmove", "memset", "memclr")
    for align in ("", "4", "8")
}


def build(probe: Path, features: list[str], target: Path, triple: str | None, cpu: str) -> Path:
    command = ["cargo", "build", "--release", "-q", "--manifest-path", str(probe / "Cargo.toml")]
    if features:
        command += ["--features", ",".join(features)]
    if triple:
        command += ["--target", triple]
    name = "-".join(features) or "codec"
    env = dict(os.environ, CARGO_TARGET_DIR=str(target / name))
    if triple:
        # Code for the core itself (its FPU), not the target's baseline.
        env["RUSTFLAGS"] = f"-C target-cpu={cpu}"
    subprocess.run(command, check=True, env=env)
    if not triple:
        return target / name / "release" / "libpx4params_size_probe.so"
    archive = target / name / triple / "release" / "libpx4params_size_probe.a"
    # The memory routines the core calls come from the C library, as in a firmware (Rust's
    # own, in `compiler_builtins`, are weak symbols that a libc's replace): named first, so
    # that the libc's are the ones linked.
    wanted = {line.split()[-1] for line in nm(["-u", str(archive)]).splitlines() if line.strip()}
    libc = [f"-Wl,--undefined={symbol}" for symbol in sorted(wanted & MEMORY_ROUTINES)]
    return link_arm([*libc, LIBC, str(archive)], EXPORTS, archive.with_suffix(".elf"), cpu)


def nm(arguments: list[str]) -> str:
    command = ["arm-none-eabi-nm", *arguments]
    return subprocess.run(command, capture_output=True, text=True, check=True).stdout


def link_arm(inputs: list[str], roots: list[str], image: Path, cpu: str) -> Path:
    """A Cortex-M image of `inputs` holding what `roots` reach (``--gc-sections``)."""
    keep = [f"-Wl,--undefined={symbol}" for symbol in roots]
    link = ["arm-none-eabi-gcc", *ARM_FLAGS[cpu], "-nostartfiles", "-nostdlib", "-Wl,--gc-sections"]
    # newlib's memcpy objects lack a .note.GNU-stack section: ld's warning says nothing here.
    link += ["-Wl,--no-warn-execstack", "-Wl,--entry=0", *keep, *inputs, LIBC, "-lgcc"]
    subprocess.run([*link, "-o", str(image)], check=True)
    return image


# The C baseline (issue 39): dronecan_dsdlc-generated C on libcanard v0, outside the project
# (../shared/anchors/dronecan-c; PX4PARAMS_C_ANCHOR elsewhere), built with gcc -Os and linked
# as the probes are: each image holds what the named API reaches, the memory routines from
# the same libc.
C_ANCHOR = Path(os.environ.get("PX4PARAMS_C_ANCHOR", ROOT.parent / "shared/anchors/dronecan-c"))
C_MESSAGES = [
    "uavcan.equipment.power.BatteryInfo",
    "uavcan.protocol.NodeStatus",
    "uavcan.protocol.GetNodeInfo_res",
    "uavcan.protocol.file.Read_res",
]


def c_baseline(work: Path, cpu: str) -> dict[str, int]:
    """``.text`` of libcanard's whole API, and with the four messages' encode/decode too."""
    work.mkdir(parents=True, exist_ok=True)
    includes = [f"-I{C_ANCHOR / 'libcanard'}", f"-I{C_ANCHOR / 'generated' / 'include'}"]
    sources = [C_ANCHOR / "libcanard" / "canard.c"]
    sources += sorted((C_ANCHOR / "generated" / "src").glob("*.c"))
    objects = []
    for source in sources:
        obj = work / (source.stem + ".o")
        compile_c = ["arm-none-eabi-gcc", *ARM_FLAGS[cpu], "-Os", "-DNDEBUG", *includes]
        subprocess.run(
            [*compile_c, "-ffunction-sections", "-c", str(source), "-o", str(obj)], check=True
        )
        objects.append(obj)

    def api(obj: Path) -> list[str]:
        out = nm(["--defined-only", "-g", str(obj)])
        return [line.split()[-1] for line in out.splitlines() if line.split()[1] == "T"]

    canard, messages = objects[0], [work / f"{m}.o" for m in C_MESSAGES]
    roots = api(canard)
    sizes = {"canard.c": text_size(link_arm([str(o) for o in objects], roots, work / "c.elf", cpu))}
    roots += [symbol for obj in messages for symbol in api(obj)]
    both = link_arm([str(o) for o in objects], roots, work / "c-messages.elf", cpu)
    sizes["canard.c + 4 messages"] = text_size(both)
    return sizes


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawTextHelpFormatter
    )
    parser.add_argument("--keep", metavar="DIR", help="build in DIR (kept; rebuilds are faster)")
    parser.add_argument("--symbols", type=int, default=0, metavar="N")
    parser.add_argument("--target", metavar="TRIPLE", choices=[t for t in TARGETS if t])
    parser.add_argument("--opt-level", choices=["s", "z"], default="z")
    parser.add_argument("--cpu", choices=list(ARM_FLAGS), default="cortex-m7")
    args = parser.parse_args()
    tools = ["cargo", "size", "nm"] + (["arm-none-eabi-gcc"] if args.target else [])
    for tool in tools:
        if shutil.which(tool) is None:
            print(f"size: {tool} is not installed", file=sys.stderr)
            return 1
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(args.keep) if args.keep else Path(tmp)
        probe = work / "probe"
        probe.mkdir(parents=True, exist_ok=True)
        core, ffi = ROOT / "crates" / "px4params-core", ROOT / "crates" / "px4params-ffi"
        crate_type = "staticlib" if args.target else "cdylib"
        toml = PROBE_TOML.format(
            core=core, ffi=ffi, crate_type=crate_type, opt_level=args.opt_level
        )
        (probe / "Cargo.toml").write_text(toml)
        (probe / "lib.rs").write_text(PROBE_RS)
        # The targets are firmware's: the core built for size (`compact`).
        print(f"{'probe':8} {'host .text':>12} {'compact .text':>14} {'target':>8}")
        failed = False
        # The ceilings hold for the Cortex-M7 (and the host); other cores are measured only.
        ceilings = TARGETS[args.target]
        if args.target and args.cpu != "cortex-m7":
            ceilings = dict.fromkeys(ceilings)
        for feature, target in ceilings.items():
            sizes = []
            for compact in (False, True):
                features = [feature] if feature != "codec" else []
                features += ["compact"] if compact else []
                library = build(probe, features, work / "target" / args.cpu, args.target, args.cpu)
                sizes.append(text_size(library))
                for line in largest(library, args.symbols):
                    print(f"    {'compact ' if compact else ''}{line}")
            host, small = sizes
            if target is None:
                print(f"{feature:8} {host:>12,} {small:>14,} {'-':>8}")
            else:
                failed |= small > target
                verdict = "ok" if small <= target else "OVER"
                print(f"{feature:8} {host:>12,} {small:>14,} {target:>8,}  {verdict}")
        if args.target:
            if (C_ANCHOR / "libcanard" / "canard.c").is_file():
                for name, size in c_baseline(work / "c" / args.cpu, args.cpu).items():
                    print(f"C: {name} (gcc -Os) .text {size:,}")
            else:
                print(f"C: baseline not measured ({C_ANCHOR} not found)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
